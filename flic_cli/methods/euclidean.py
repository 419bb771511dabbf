"""Euclidean clustering, PCL's ``EuclideanClusterExtraction``: the connected components of the
graph that links every two points closer than a tolerance (Rusu, "Semantic 3D Object Maps for
Everyday Manipulation in Human Living Environments", PhD thesis, 2009, section 4.2).

PCL grows each cluster by radius searches from a seed; the result is exactly the connected
components of the radius graph (pairs strictly closer than the tolerance: FLANN's radius search,
which PCL's ``KdTreeFLANN`` calls, keeps ``dist < radius``; checked with PCL 1.13 on points exactly
0.5 m apart), and clusters outside ``[min_size, max_size]`` points are dropped. The tolerance
defaults to the 0.5 m of the ICCVW 2021 survey of traditional clusterers (Zhao, Zhang, Patel:
"Towards Fast LiDAR Panoptic Segmentation without Training", ICCVW 2021); the sweeps of
results/peers/sweeps/ confirm it.

The components are found without listing the graph's pairs (a dense LiDAR frame has tens of
millions of them), on a grid of cubic cells of side ``tolerance / sqrt(3)``, the grid method of
grid DBSCAN (Gunawan, "A Faster Algorithm for DBSCAN", MSc thesis, TU Eindhoven, 2013) with
every point a core point:

1. two points of one cell are closer than the cell's diagonal, the tolerance: a cell's points
   are one component;
2. two points of cells whose index differs by 3 or more along an axis are more than
   ``2 * tolerance / sqrt(3) > tolerance`` apart: only cells at the 124 offsets in ``{-2..2}^3``
   can link (62, one of each +- pair, are tested);
3. a candidate pair of cells is linked when any of its point pairs is closer than the
   tolerance; it is tested only when the two cells are not yet in one component (a union-find
   over cells), the closest offsets first, and the test stops at the first linking pair.

In a dense region most candidate pairs are decided by their first point pairs or skipped as
already joined, so the cost follows the number of points and cells, not of pairs; memory is
``O(N)``. The result is the radius graph's partition exactly (tests/test_peers.py checks it
against the brute-force graph, points exactly at the tolerance included). Distances are computed
in float64 (PCL: float32), which can differ only for pairs within ~1e-7 of the tolerance.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, ClassVar

import numpy as np
from numba import njit
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.component import STRICT
from flic_cli.methods._peers import cluster_kept
from flic_cli.methods.base import drop_small
from flic_cli.range_image import RangeImage

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground


@dataclass(frozen=True, config=STRICT)
class Euclidean:
    """PCL's Euclidean cluster extraction as a :class:`flic_cli.methods.base.Method`.

    Attributes
    ----------
    tolerance_m : two points closer than this are linked, metres.
    min_size : smallest cluster kept, points (PCL's ``setMinClusterSize``).
    max_size : largest cluster kept, points (PCL's ``setMaxClusterSize``; its default,
        ``INT_MAX``).
    """

    tolerance_m: Annotated[float, Field(gt=0, description="link distance, metres")] = 0.5
    min_size: Annotated[int, Field(ge=1, description="smallest cluster kept, points")] = 100
    max_size: Annotated[int, Field(ge=1, description="largest cluster kept, points")] = 2**31 - 1
    main_param: ClassVar[str] = "tolerance_m"
    sweep_range: ClassVar[tuple[float, float, float]] = (0.1, 1.5, 0.1)
    slow: ClassVar[bool] = False
    sweep_label: ClassVar[str] = "Euclidean tolerance [m]"

    def segment(self, image: RangeImage, points: np.ndarray, ground: Ground | None) -> np.ndarray:
        labels = cluster_kept(
            image, points, ground, lambda p, _: radius_components(p, self.tolerance_m) + 1,
            self.min_size,
        )  # fmt: skip
        if labels.size:
            counts = np.bincount(labels)
            too_big = np.flatnonzero(counts > self.max_size)
            too_big = too_big[too_big > 0]
            if too_big.size:
                labels = labels.copy()
                labels[np.isin(labels, too_big)] = 0
                labels = drop_small(labels, 1)
        return labels


#: Relative amount by which a cell's side is under ``tolerance / sqrt(3)`` (float rounding).
CELL_SHRINK = 1e-9

#: Cell offsets (dx, dy, dz) in ``{-2..2}^3`` that can hold a linked pair, one of each +- pair,
#: the closest first (by the smallest possible distance between their cells, then by |d|).
_OFFSETS = sorted(
    (
        (dx, dy, dz)
        for dx in range(-2, 3)
        for dy in range(-2, 3)
        for dz in range(-2, 3)
        if (dx, dy, dz) > (0, 0, 0)
    ),
    key=lambda d: (sum(max(abs(v) - 1, 0) ** 2 for v in d), sum(abs(v) for v in d), d),
)


def radius_components(points: np.ndarray, radius_m: float) -> np.ndarray:
    """(N,) component id (0..K-1) of every point in the graph linking points closer than
    ``radius_m``.

    Parameters
    ----------
    points : (N, 3+) metres (the first three columns are used), finite.
    radius_m : link distance, metres (pairs strictly closer are linked, as in PCL).

    Returns
    -------
    (N,) int64, ids in order of first point.
    """
    xyz = np.ascontiguousarray(points[:, :3], dtype=np.float64)
    n = xyz.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    # slightly under r / sqrt(3): two points of one cell are closer than r
    side = radius_m / np.sqrt(3.0) * (1.0 - CELL_SHRINK)
    cell = np.floor((xyz - xyz.min(axis=0)) / side).astype(np.int64) + 2
    dims = cell.max(axis=0) + 3
    if float(dims[0]) * float(dims[1]) * float(dims[2]) >= 2.0**62:
        raise ValueError(f"points span too many {side:.3g} m cells for one int64 key")
    stride = np.array([dims[1] * dims[2], dims[2], 1], dtype=np.int64)
    key = cell @ stride
    order = np.argsort(key, kind="stable")
    ucell, start, count = np.unique(key[order], return_index=True, return_counts=True)
    a_list, b_list = [], []
    for off in _OFFSETS:
        want = ucell + int(np.dot(off, stride))
        pos = np.searchsorted(ucell, want)
        pos[pos == ucell.size] = 0
        hit = np.flatnonzero(ucell[pos] == want)
        a_list.append(hit)
        b_list.append(pos[hit])
    a = np.concatenate(a_list).astype(np.int64)
    b = np.concatenate(b_list).astype(np.int64)
    root = _link_cells(
        xyz[order], start.astype(np.int64), count.astype(np.int64), a, b, float(radius_m) ** 2
    )
    cell_of_sorted = np.repeat(np.arange(ucell.size), count)
    comp = np.empty(n, dtype=np.int64)
    comp[order] = root[cell_of_sorted]
    _, first, inverse = np.unique(comp, return_index=True, return_inverse=True)
    rank = np.empty(first.size, dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(first.size)
    return rank[inverse.reshape(-1)]


@njit(cache=True)
def _find(parent: np.ndarray, i: int) -> int:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True)
def _link_cells(
    xyz: np.ndarray,
    start: np.ndarray,
    count: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    r2: float,
) -> np.ndarray:
    """Union-find root of every cell after testing the candidate cell pairs ``a``-``b`` in order
    (points sorted by cell; cell c holds ``xyz[start[c]:start[c] + count[c]]``)."""
    parent = np.arange(start.size)
    for k in range(a.size):
        ra = _find(parent, a[k])
        rb = _find(parent, b[k])
        if ra == rb:
            continue
        linked = False
        for i in range(start[a[k]], start[a[k]] + count[a[k]]):
            x, y, z = xyz[i, 0], xyz[i, 1], xyz[i, 2]
            for j in range(start[b[k]], start[b[k]] + count[b[k]]):
                dx = xyz[j, 0] - x
                dy = xyz[j, 1] - y
                dz = xyz[j, 2] - z
                if dx * dx + dy * dy + dz * dz < r2:
                    linked = True
                    break
            if linked:
                break
        if linked:
            parent[max(ra, rb)] = min(ra, rb)
    for c in range(start.size):
        parent[c] = _find(parent, c)
    return parent

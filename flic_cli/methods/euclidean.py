"""Euclidean clustering, PCL's ``EuclideanClusterExtraction``: the connected components of the
graph that links every two points closer than a tolerance (Rusu, "Semantic 3D Object Maps for
Everyday Manipulation in Human Living Environments", PhD thesis, 2009, section 4.2).

PCL grows each cluster by radius searches from a seed; the result is exactly the connected
components of the radius graph, which this module builds with :class:`scipy.spatial.cKDTree`
and labels with :func:`scipy.sparse.csgraph.connected_components`. The tolerance defaults to the
0.5 m of the ICCVW 2021 survey of traditional clusterers (Zhao, Zhang, Patel: "Towards
Fast LiDAR Panoptic Segmentation without Training", ICCVW 2021).

Memory is bounded: exactly coinciding points are merged first (they are always linked), and
when the tree's pair count (:meth:`scipy.spatial.cKDTree.count_neighbors`, no pairs stored)
exceeds :data:`PAIR_BUDGET`, the pairs are built in chunks of points whose neighbour counts sum
to at most the budget (:meth:`scipy.spatial.cKDTree.sparse_distance_matrix` of the chunk against
all points), the components merged chunk by chunk. A dense blob of points thus costs
time, never more than ``PAIR_BUDGET + N`` stored pairs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, ClassVar

import numpy as np
from pydantic import Field
from pydantic.dataclasses import dataclass
from scipy.spatial import cKDTree

from flic_cli.component import STRICT
from flic_cli.methods._peers import cluster_kept, components
from flic_cli.range_image import RangeImage

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground

#: Most point pairs held in memory at once (8 bytes per index: 2**23 pairs = 128 MiB).
PAIR_BUDGET = 1 << 23


@dataclass(frozen=True, config=STRICT)
class Euclidean:
    """PCL's Euclidean cluster extraction as a :class:`flic_cli.methods.base.Method`.

    Attributes
    ----------
    tolerance_m : two points closer than this (or at exactly this distance) are linked, metres.
    min_size : smallest cluster kept, points.
    """

    tolerance_m: Annotated[float, Field(gt=0, description="link distance, metres")] = 0.5
    min_size: Annotated[int, Field(ge=1, description="smallest cluster kept, points")] = 100
    main_param: ClassVar[str] = "tolerance_m"
    sweep_range: ClassVar[tuple[float, float, float]] = (0.1, 1.5, 0.1)
    slow: ClassVar[bool] = False
    sweep_label: ClassVar[str] = "Euclidean tolerance [m]"

    def segment(self, image: RangeImage, points: np.ndarray, ground: Ground | None) -> np.ndarray:
        return cluster_kept(
            image, points, ground, lambda p, _: radius_components(p, self.tolerance_m) + 1,
            self.min_size,
        )  # fmt: skip


def radius_components(
    points: np.ndarray, radius_m: float, pair_budget: int = PAIR_BUDGET
) -> np.ndarray:
    """(N,) component id (0..K-1) of every point in the graph linking points within ``radius_m``.

    Parameters
    ----------
    points : (N, 3+) metres (the first three columns are used).
    radius_m : link distance, metres (pairs at a distance <= radius are linked).
    pair_budget : most pairs held at once (module docstring).
    """
    xyz = np.ascontiguousarray(points[:, :3], dtype=np.float64)
    n = xyz.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    uniq, inverse = np.unique(xyz, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    m = uniq.shape[0]
    tree = cKDTree(uniq)
    ordered = int(tree.count_neighbors(tree, radius_m)) - m  # ordered pairs, no self pairs
    if ordered // 2 <= pair_budget:
        pairs = tree.query_pairs(radius_m, output_type="ndarray")
        comp = components(m, pairs[:, 0], pairs[:, 1])
        return comp[inverse]
    counts = np.asarray(tree.query_ball_point(uniq, radius_m, return_length=True), dtype=np.int64)
    comp = np.arange(m)
    start = 0
    while start < m:
        # the longest run of points from ``start`` whose neighbour lists fit the budget
        stop = start + max(1, int(np.searchsorted(np.cumsum(counts[start:]), pair_budget)))
        stop = min(stop, m)
        pairs = cKDTree(uniq[start:stop]).sparse_distance_matrix(
            tree, radius_m, output_type="ndarray"
        )
        a = pairs["i"].astype(np.int64) + start
        b = pairs["j"].astype(np.int64)
        merged = components(m, comp[a], comp[b])
        comp = merged[comp]
        start = stop
    _, comp = np.unique(comp, return_inverse=True)
    return comp.reshape(-1)[inverse]

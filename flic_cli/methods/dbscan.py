"""DBSCAN on the 3D points of the non-ground point set.

Two backends compute it:

- ``"sklearn"`` (the reference, default): :class:`sklearn.cluster.DBSCAN`, 0.2-0.5 s per
  SemanticKITTI frame on one core.
- ``"fastdbscan"``: the ``dbscan`` package (Wang, Gu, Shun: "Theoretically-Efficient and Practical
  Parallel DBSCAN", SIGMOD 2020; ``pip install 'flic[fastdbscan]'``), grid-based and parallel
  (threads: ``PARLAY_NUM_THREADS``, read once when it first runs).

Measured on the 50 shared frames, no-ground point sets, one thread each, same process
(``results/dbscan-backends/summary.csv``, its command in
``results/README.md``): median 190 ms (scikit-learn) against 41 ms (the package), 4.5 times
faster; adjusted Rand index of the final labels >= 0.9936, IoU_mu 86.38 against 86.38, P_mu equal.
Of 2.4 million points, 298 end in another cluster or in noise (873 before the 100-point minimum).
Among the latter: 710 border points within ``eps`` of core points of two clusters, given to the
other one (DBSCAN leaves that open), and 114 points that scikit-learn takes as core points but
the package does not (110 of them with exactly ``min_samples`` neighbours within ``eps``, none
closer than 7e-5 m to ``eps``; the package's answer there depends on points far away), which
turns 78 border points into noise.
"""

from __future__ import annotations

import importlib.util
from typing import TYPE_CHECKING, Annotated, ClassVar, Literal

import numpy as np
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.component import STRICT
from flic_cli.errors import FlicInputError
from flic_cli.methods.base import drop_small, ground_parts
from flic_cli.range_image import RangeImage

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground

BACKENDS = ("sklearn", "fastdbscan")


def raw_dbscan(
    points: np.ndarray, eps_m: float, min_samples: int, backend: str = "sklearn"
) -> tuple[np.ndarray, np.ndarray]:
    """DBSCAN labels as the backend returns them (-1 = noise, 0..K-1) and the core-point mask.

    Parameters
    ----------
    points : (N, 3+) metres (only the first three columns are used).
    eps_m, min_samples : as :func:`dbscan_labels`.
    backend : ``"sklearn"`` or ``"fastdbscan"`` (module docstring).
    """
    xyz = np.ascontiguousarray(points[:, :3], dtype=np.float64)
    if backend == "sklearn":
        from sklearn.cluster import DBSCAN

        weight, inverse = None, None
        if neighbour_pairs_bound(xyz, eps_m) > MAX_NEIGHBOUR_PAIRS:
            # coinciding points: one point per place, weighted by its count (DBSCAN with
            # sample_weight gives every copy the labels of its place)
            unique, inverse, weight = np.unique(
                xyz, axis=0, return_inverse=True, return_counts=True
            )
            xyz, inverse = unique, inverse.reshape(-1)
            if neighbour_pairs_bound(xyz, eps_m) > MAX_NEIGHBOUR_PAIRS:
                from sklearn.neighbors import KDTree  # the exact count, in O(N) memory

                pairs = int(KDTree(xyz).query_radius(xyz, eps_m, count_only=True).sum())
                if pairs > MAX_NEIGHBOUR_PAIRS:
                    raise FlicInputError(
                        None,
                        f"DBSCAN: {points.shape[0]} points lie too densely for eps {eps_m:g} m: "
                        f"{pairs:.3g} neighbour pairs, beyond the budget of "
                        f"{MAX_NEIGHBOUR_PAIRS:.3g} (flic_cli.methods.dbscan."
                        "MAX_NEIGHBOUR_PAIRS, 8 bytes each); use a smaller eps_m",
                    )
        est = DBSCAN(eps=eps_m, min_samples=min_samples, n_jobs=1).fit(xyz, sample_weight=weight)
        core = np.zeros(xyz.shape[0], dtype=bool)
        core[est.core_sample_indices_] = True
        labels = est.labels_.astype(np.int64)
        if inverse is not None:
            return labels[inverse], core[inverse]
        return labels, core
    if backend == "fastdbscan":
        from dbscan import DBSCAN as fast_dbscan

        labels, core = fast_dbscan(xyz, eps=float(eps_m), min_samples=int(min_samples))
        return np.asarray(labels, dtype=np.int64), np.asarray(core, dtype=bool)
    raise ValueError(f"unknown DBSCAN backend {backend!r} ({' | '.join(BACKENDS)})")


#: The memory bound of the ``sklearn`` backend, in neighbour pairs. scikit-learn's DBSCAN stores
#: every point's whole neighbourhood (8 bytes per pair), so points that coincide, or nearly so,
#: take O(N^2) memory: 20 GB and more for one frame. 5e8 pairs = 3.7 GiB. Whole SemanticKITTI
#: scans (124 k points) have 3.5e7 pairs at eps 0.5 m and 2.5e8 at 1.5 m (grid bound 9.8e7 and
#: 6.1e8, the densest of ten shared frames). When the grid bound
#: (:func:`neighbour_pairs_bound`) exceeds it, :func:`raw_dbscan` merges coinciding points into one
#: point weighted by their number (``sample_weight``: the same DBSCAN), then counts the pairs
#: exactly (a KD-tree, O(N) memory) and refuses the frame, with an error naming it, only if
#: they still exceed the budget.
MAX_NEIGHBOUR_PAIRS = 500_000_000


def neighbour_pairs_bound(xyz: np.ndarray, eps_m: float) -> int:
    """An upper bound of the ordered point pairs within ``eps_m`` (self pairs included), in O(N).

    Every pair within ``eps_m`` lies in the same or in adjacent cells of a grid of side
    ``eps_m``, so the sum over cells of (points in the cell) x (points in its 27 cells) bounds
    their number from above (by about 27 / (4/3 pi) = 6.4 times for evenly spread points).

    Parameters
    ----------
    xyz : (N, 3) float64 metres, finite.
    eps_m : neighbourhood radius, metres.
    """
    if xyz.shape[0] == 0:
        return 0
    cells = np.floor(xyz / eps_m).astype(np.int64)
    cells -= cells.min(axis=0) - 1  # >= 1, so that the neighbours' keys stay >= 0
    span = cells.max(axis=0) + 2
    if float(np.prod(span.astype(np.float64))) >= 2.0**62:
        return int(xyz.shape[0]) ** 2  # cannot key the cells: assume the worst
    keys, counts = np.unique(
        (cells[:, 0] * span[1] + cells[:, 1]) * span[2] + cells[:, 2], return_counts=True
    )
    around = np.zeros(keys.size, dtype=np.int64)
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                other = keys + (dx * span[1] + dy) * span[2] + dz
                at = np.minimum(np.searchsorted(keys, other), keys.size - 1)
                around += np.where(keys[at] == other, counts[at], 0)
    return int(np.dot(counts, around))


@dataclass(frozen=True, config=STRICT)
class Dbscan:
    """DBSCAN as a :class:`flic_cli.methods.base.Method`; ground pixels' points are left out.

    Attributes
    ----------
    eps_m : neighbourhood radius, metres.
    min_samples : points in the radius (the point itself included) that make a core point.
    min_size : smallest cluster kept, points.
    backend : ``"sklearn"`` (the reference) or ``"fastdbscan"`` (the ``dbscan`` package: the same
        clusters up to a few border points, about four times faster on one core; module doc).
    """

    eps_m: Annotated[float, Field(gt=0, description="neighbourhood radius, metres")] = 0.5
    min_samples: Annotated[int, Field(ge=1, description="points that make a core point")] = 5
    min_size: Annotated[int, Field(ge=1, description="smallest cluster kept, points")] = 100
    backend: Literal["sklearn", "fastdbscan"] = "sklearn"
    main_param: ClassVar[str] = "eps_m"
    sweep_range: ClassVar[tuple[float, float, float]] = (0.2, 1.5, 0.1)
    sweep_label: ClassVar[str] = "DBSCAN eps [m]"
    slow: ClassVar[bool] = True

    def check_installed(self) -> None:
        """Fail with the install hint when the chosen backend's package is missing."""
        if self.backend == "fastdbscan" and importlib.util.find_spec("dbscan") is None:
            raise FlicInputError(
                None,
                "backend 'fastdbscan' needs the package dbscan: pip install 'flic[fastdbscan]'",
            )

    def segment(self, image: RangeImage, points: np.ndarray, ground: Ground | None) -> np.ndarray:
        left_out, attached = ground_parts(ground)
        pix = image.point_pixel
        keep = pix >= 0
        if left_out is not None:
            keep &= ~left_out.reshape(-1)[np.maximum(pix, 0)]
        out = np.zeros(points.shape[0], dtype=np.int32)
        if attached is None or not len(attached):
            out[keep] = dbscan_labels(
                points[keep], self.eps_m, self.min_samples, self.min_size, self.backend
            )
            return out
        # held pixels (in ``left_out``): their points take the cluster of a point of the
        # pixel standing on them and count towards its size
        out[keep] = dbscan_labels(points[keep], self.eps_m, self.min_samples, 1, self.backend)
        cell = np.zeros(image.ranges.size, dtype=np.int32)
        cell[pix[keep]] = out[keep]
        held, target = attached[:, 0], attached[:, 1]
        cell[held] = np.where(target >= 0, cell[np.maximum(target, 0)], 0)
        is_held = np.zeros(image.ranges.size, dtype=bool)
        is_held[held] = True
        moved = (pix >= 0) & is_held[np.maximum(pix, 0)]
        out[moved] = cell[pix[moved]]
        return drop_small(out, self.min_size)


def dbscan_labels(
    points: np.ndarray,
    eps_m: float = Dbscan.eps_m,
    min_samples: int = Dbscan.min_samples,
    min_size: int = Dbscan.min_size,
    backend: str = Dbscan.backend,
) -> np.ndarray:
    """DBSCAN cluster labels of 3D points.

    Parameters
    ----------
    points : (N, 3) metres.
    eps_m : neighbourhood radius, metres.
    min_samples : points (the point itself included) in the radius that make a core point.
    min_size : clusters with fewer points are dropped, as for the image methods.
    backend : ``"sklearn"`` (reference) or ``"fastdbscan"`` (module docstring).

    Returns
    -------
    (N,) int32, 0 = noise or dropped, 1..K clusters in order of first point.
    """
    if points.shape[0] == 0:
        return np.zeros(0, dtype=np.int32)
    raw, _ = raw_dbscan(points, eps_m, min_samples, backend)
    return drop_small(raw + 1, min_size)

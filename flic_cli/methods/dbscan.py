"""DBSCAN on the 3D points of the non-ground point set.

Two backends compute it:

- ``"sklearn"`` (the reference, default): :class:`sklearn.cluster.DBSCAN`, 0.2-0.5 s per
  SemanticKITTI frame on one core.
- ``"fastdbscan"``: the ``dbscan`` package (Wang, Gu, Shun: "Theoretically-Efficient and Practical
  Parallel DBSCAN", SIGMOD 2020; ``pip install 'flic[fastdbscan]'``), grid-based and parallel
  (threads: ``PARLAY_NUM_THREADS``, read once when it first runs).

Measured on the 50 shared frames, no-ground point sets, one thread each, same process
(``python scripts/dbscan_backends.py ../shared/data/semantickitti results/dbscan-backends``,
``summary.csv`` there): median 190 ms (scikit-learn) against 41 ms (the package), 4.5 times
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

        est = DBSCAN(eps=eps_m, min_samples=min_samples, n_jobs=1).fit(xyz)
        core = np.zeros(xyz.shape[0], dtype=bool)
        core[est.core_sample_indices_] = True
        return est.labels_.astype(np.int64), core
    if backend == "fastdbscan":
        from dbscan import DBSCAN as fast_dbscan

        labels, core = fast_dbscan(xyz, eps=float(eps_m), min_samples=int(min_samples))
        return np.asarray(labels, dtype=np.int64), np.asarray(core, dtype=bool)
    raise ValueError(f"unknown DBSCAN backend {backend!r} ({' | '.join(BACKENDS)})")


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

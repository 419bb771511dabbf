"""HDBSCAN on the 3D points (Campello, Moulavi, Sander, PAKDD 2013), scikit-learn's
:class:`sklearn.cluster.HDBSCAN`: the density-based hierarchy of DBSCAN over every radius,
its clusters chosen by stability, so no single radius is set. ``min_cluster_size`` 30 from the
sweep of results/peers/sweeps/hdbscan/ (5 shared frames: 87.48 against 90.45 at 70; 2 sample
frames: 65.98, their best; the smallest loss on either of 10, 20, 30, 50 and 70).

It takes 15-60 s per SemanticKITTI frame on one core (``slow``: ``flic benchmark`` times it on
every n-th frame only, as DBSCAN).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, ClassVar

import numpy as np
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.component import STRICT
from flic_cli.methods._peers import cluster_kept
from flic_cli.range_image import RangeImage

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground


@dataclass(frozen=True, config=STRICT)
class Hdbscan:
    """scikit-learn's HDBSCAN as a :class:`flic_cli.methods.base.Method`.

    Attributes
    ----------
    min_cluster_size : smallest group HDBSCAN calls a cluster, points.
    min_samples : neighbours that define a point's core distance (0: ``min_cluster_size``, as
        scikit-learn's None).
    cluster_selection_epsilon_m : clusters closer than this are not split, metres (0: off).
    min_size : smallest cluster kept afterwards, points (as for every method).
    """

    min_cluster_size: Annotated[int, Field(ge=2, description="HDBSCAN's smallest cluster")] = 30
    min_samples: Annotated[
        int, Field(ge=0, description="core distance neighbours (0: min_cluster_size)")
    ] = 0
    cluster_selection_epsilon_m: Annotated[
        float, Field(ge=0, description="clusters closer than this are merged, metres")
    ] = 0.0
    min_size: Annotated[int, Field(ge=1, description="smallest cluster kept, points")] = 100
    main_param: ClassVar[str] = "min_cluster_size"
    sweep_range: ClassVar[tuple[float, float, float]] = (10, 100, 15)
    slow: ClassVar[bool] = True
    sweep_label: ClassVar[str] = "HDBSCAN min_cluster_size [points]"

    def segment(self, image: RangeImage, points: np.ndarray, ground: Ground | None) -> np.ndarray:
        return cluster_kept(image, points, ground, lambda p, _: self.raw(p) + 1, self.min_size)

    def raw(self, points: np.ndarray) -> np.ndarray:
        """HDBSCAN's labels of (N, 3) points as scikit-learn returns them (-1 = noise)."""
        if points.shape[0] < 2:
            return np.full(points.shape[0], -1, dtype=np.int64)
        from sklearn.cluster import HDBSCAN

        est = HDBSCAN(
            min_cluster_size=min(self.min_cluster_size, points.shape[0]),
            min_samples=self.min_samples or None,
            cluster_selection_epsilon=self.cluster_selection_epsilon_m,
            copy=True,
        )
        return est.fit_predict(np.asarray(points[:, :3], dtype=np.float64)).astype(np.int64)

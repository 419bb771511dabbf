"""DBSCAN (scikit-learn) on the 3D points of the non-ground point set."""

from __future__ import annotations

from typing import Annotated, ClassVar

import numpy as np
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.config.component import STRICT
from flic_cli.methods.base import drop_small
from flic_cli.range_image import RangeImage


def dbscan_labels(
    points: np.ndarray, eps_m: float = 0.5, min_samples: int = 5, min_size: int = 100
) -> np.ndarray:
    """DBSCAN cluster labels of 3D points.

    Parameters
    ----------
    points : (N, 3) metres.
    eps_m : neighbourhood radius, metres.
    min_samples : points (the point itself included) in the radius that make a core point.
    min_size : clusters with fewer points are dropped, as for the image methods.

    Returns
    -------
    (N,) int32, 0 = noise or dropped, 1..K clusters.
    """
    from sklearn.cluster import DBSCAN

    if points.shape[0] == 0:
        return np.zeros(0, dtype=np.int32)
    raw = DBSCAN(eps=eps_m, min_samples=min_samples, n_jobs=1).fit_predict(points[:, :3])
    return drop_small(raw + 1, min_size)


@dataclass(frozen=True, config=STRICT)
class Dbscan:
    """DBSCAN as a :class:`flic_cli.methods.base.Method`; ground pixels' points are left out.

    Attributes
    ----------
    eps_m : neighbourhood radius, metres.
    min_samples : points in the radius (the point itself included) that make a core point.
    min_size : smallest cluster kept, points.
    """

    eps_m: Annotated[float, Field(gt=0, description="neighbourhood radius, metres")] = 0.5
    min_samples: Annotated[int, Field(ge=1, description="points that make a core point")] = 5
    min_size: Annotated[int, Field(ge=1, description="smallest cluster kept, points")] = 100
    main_param: ClassVar[str] = "eps_m"

    def segment(
        self, image: RangeImage, points: np.ndarray, ground: np.ndarray | None
    ) -> np.ndarray:
        keep = image.point_pixel >= 0
        if ground is not None:
            keep &= ~ground.reshape(-1)[np.maximum(image.point_pixel, 0)]
        out = np.zeros(points.shape[0], dtype=np.int32)
        out[keep] = dbscan_labels(points[keep], self.eps_m, self.min_samples, self.min_size)
        return out

"""Bogoslavskyi & Stachniss' range-image segmentation (IROS 2016)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, ClassVar

import numpy as np
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.component import STRICT
from flic_cli.methods.connections import ANGLE, run_kernel, segment_image
from flic_cli.methods.flic import cached_sets
from flic_cli.range_image import RangeImage

if TYPE_CHECKING:
    from flic_cli.ground.base import Ground

#: the key of the direct connections alone (see :func:`flic_cli.methods.flic.cached_sets`)
DIRECT = ((), "map")


def bogoslavskyi_beta(d1: np.ndarray, d2: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Their angle ``beta = atan2(d_min sin(alpha), d_max - d_min cos(alpha))``, radians."""
    big = np.maximum(d1, d2)
    small = np.minimum(d1, d2)
    return np.arctan2(small * np.sin(alpha), big - small * np.cos(alpha))


@dataclass(frozen=True, config=STRICT)
class Bogoslavskyi:
    """Bogoslavskyi & Stachniss as a :class:`flic_cli.methods.base.Method`.

    Attributes
    ----------
    angle_deg : neighbours join when their angle beta exceeds this, degrees.
    min_size : smallest cluster kept, points of the evaluated set (a pixel counts its points).
    """

    angle_deg: Annotated[float, Field(gt=0, lt=90, description="angle threshold, degrees")] = 10.0
    min_size: Annotated[int, Field(ge=1, description="smallest cluster kept, points")] = 100
    main_param: ClassVar[str] = "angle_deg"
    sweep_range: ClassVar[tuple[float, float, float]] = (2.0, 30.0, 1.0)
    sweep_label: ClassVar[str] = "angle threshold beta [deg]"
    slow: ClassVar[bool] = False

    def segment(self, image: RangeImage, points: np.ndarray, ground: Ground | None) -> np.ndarray:
        param = float(np.tan(np.radians(self.angle_deg)))
        return segment_image(
            image, ground, cached_sets(*DIRECT), DIRECT, ANGLE, param, self.min_size
        )


def bogoslavskyi_labels(
    ranges: np.ndarray,
    elevation: np.ndarray,
    angle_deg: float = Bogoslavskyi.angle_deg,
    min_size: int = Bogoslavskyi.min_size,
    mask: np.ndarray | None = None,
    weights: np.ndarray | None = None,
    azimuth_offset: np.ndarray | None = None,
) -> np.ndarray:
    """Cluster labels by the angle criterion: 4-neighbours (wrapping) join when beta > angle_deg.

    The test is done without arctan: ``beta > theta`` iff ``d_min sin(alpha) > tan(theta) *
    (d_max - d_min cos(alpha))`` or the right-hand bracket is not positive (beta >= 90 deg).

    Parameters
    ----------
    ranges : (H, W) float32, metres, 0 = none.
    elevation : (H,) radians.
    angle_deg : the threshold theta, degrees (10 in the original).
    min_size : smallest cluster, points (the sum of its pixels' ``weights``).
    mask : pixels to cluster (default: valid ones; a pixel without a range is never clustered).
    weights : (H, W) int, points per pixel (default 1: the minimum size counts pixels).
    azimuth_offset : (H,) azimuth offset of every row, radians (default zeros; see
        :func:`flic_cli.methods.flic.flic_labels`).

    Returns
    -------
    (H, W) int32 labels, 0 = none.
    """
    skip = None if mask is None else ~np.asarray(mask, dtype=bool)
    return run_kernel(
        ranges,
        elevation,
        cached_sets((), "map"),
        DIRECT,
        ANGLE,
        float(np.tan(np.radians(angle_deg))),
        min_size,
        skip,
        weights,
        azimuth_offset=azimuth_offset,
    )

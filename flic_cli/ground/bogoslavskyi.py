"""Bogoslavskyi & Stachniss' ground removal (IROS 2016; depth_clustering's DepthGroundRemover)."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from numba import njit
from pydantic import Field
from pydantic.dataclasses import dataclass
from scipy.ndimage import correlate1d

from flic_cli.config.component import STRICT
from flic_cli.range_image import RangeImage

# Savitzky-Golay smoothing kernels (quadratic fit) for the window sizes the original supports.
_SG = {
    5: np.array([-3, 12, 17, 12, -3]) / 35.0,
    7: np.array([-2, 3, 6, 7, 6, 3, -2]) / 21.0,
    9: np.array([-21, 14, 39, 54, 59, 54, 39, 14, -21]) / 231.0,
    11: np.array([-36, 9, 44, 69, 84, 89, 84, 69, 44, 9, -36]) / 429.0,
}


@njit(cache=True)
def _angle_image(ranges: np.ndarray, sin_el: np.ndarray, cos_el: np.ndarray) -> np.ndarray:
    """Inclination (radians) of the line from each cell to the cell below; 0 if either is empty."""
    h, w = ranges.shape
    out = np.zeros((h, w), dtype=np.float32)
    for r in range(h - 1):
        for c in range(w):
            a = ranges[r, c]
            b = ranges[r + 1, c]
            if a > 0.0 and b > 0.0:
                dx = abs(a * cos_el[r] - b * cos_el[r + 1])
                dz = abs(a * sin_el[r] - b * sin_el[r + 1])
                out[r, c] = np.arctan2(dz, dx)
    if h > 1:
        out[h - 1, :] = out[h - 2, :]
    return out


@njit(cache=True)
def _grow_ground(
    ranges: np.ndarray, angles: np.ndarray, threshold: float, start_threshold: float
) -> np.ndarray:
    """Breadth-first growth from the lowest valid pixel of every column over similar angles."""
    h, w = ranges.shape
    ground = np.zeros((h, w), dtype=np.bool_)
    stack = np.empty(h * w, dtype=np.int64)
    for c in range(w):
        r = h - 1
        while r > 0 and ranges[r, c] <= 0.0:
            r -= 1
        if ranges[r, c] <= 0.0 or ground[r, c] or angles[r, c] > start_threshold:
            continue
        ground[r, c] = True
        top = 0
        stack[top] = r * w + c
        top += 1
        while top > 0:
            top -= 1
            i = stack[top]
            pr = i // w
            pc = i - pr * w
            a = angles[pr, pc]
            for k in range(4):
                nr = pr
                nc = pc
                if k == 0:
                    nr = pr - 1
                elif k == 1:
                    nr = pr + 1
                elif k == 2:
                    nc = pc - 1 if pc > 0 else w - 1
                else:
                    nc = pc + 1 if pc < w - 1 else 0
                if nr < 0 or nr >= h or ground[nr, nc] or ranges[nr, nc] <= 0.0:
                    continue
                if abs(angles[nr, nc] - a) < threshold:
                    ground[nr, nc] = True
                    stack[top] = nr * w + nc
                    top += 1
    # Dilate vertically by one pixel, as the original does, restricted to valid pixels.
    out = ground.copy()
    for r in range(h):
        for c in range(w):
            if not ground[r, c] and ranges[r, c] > 0.0:
                if (r > 0 and ground[r - 1, c]) or (r < h - 1 and ground[r + 1, c]):
                    out[r, c] = True
    return out


def bogoslavskyi_ground(
    image: RangeImage,
    angle_deg: float = 9.0,
    window: int = 5,
    start_angle_deg: float = 30.0,
) -> np.ndarray:
    """Ground pixels by Bogoslavskyi & Stachniss' angle-image method.

    1. Angle image: inclination ``atan2(|dz|, |dx|)`` between vertically adjacent measurements.
    2. Savitzky-Golay smoothing of every column (``window`` rows, quadratic).
    3. From the lowest valid pixel of every column whose angle is below ``start_angle_deg``, grow
       over 4-neighbours (wrapping around) whose smoothed angles differ by less than ``angle_deg``.
    4. Dilate the grown region by one row up and down.

    The original's depth in-painting before step 1 is not reproduced (it changes no label on the
    dense range images used here and costs time).

    Parameters
    ----------
    image : the range image.
    angle_deg : largest angle difference between neighbouring ground cells, degrees.
    window : Savitzky-Golay window (5, 7, 9 or 11 rows).
    start_angle_deg : a column's lowest cell seeds the growth only below this inclination, degrees.

    Returns
    -------
    (H, W) bool, True = ground.
    """
    if window not in _SG:
        raise ValueError(f"Savitzky-Golay window must be one of {sorted(_SG)}, got {window}")
    el = image.elevation
    angles = _angle_image(image.ranges, np.sin(el), np.cos(el))
    smooth = correlate1d(angles, _SG[window].astype(np.float32), axis=0, mode="mirror")
    return _grow_ground(
        image.ranges, smooth, float(np.radians(angle_deg)), float(np.radians(start_angle_deg))
    )


@dataclass(frozen=True, config=STRICT)
class BogoslavskyiGround:
    """Bogoslavskyi & Stachniss' ground removal as a :class:`flic_cli.ground.base.GroundRemover`.

    Attributes
    ----------
    angle_deg : largest angle difference between neighbouring ground cells, degrees.
    window : Savitzky-Golay window, rows.
    start_angle_deg : a column's lowest cell seeds the growth only below this angle, degrees.
    """

    angle_deg: Annotated[float, Field(gt=0, lt=90, description="degrees")] = 9.0
    window: Literal[5, 7, 9, 11] = 5
    start_angle_deg: Annotated[float, Field(gt=0, lt=90, description="degrees")] = 30.0

    def __call__(self, image: RangeImage, points: np.ndarray | None = None) -> np.ndarray:
        """(H, W) bool ground mask of ``image`` (see :func:`bogoslavskyi_ground`)."""
        return bogoslavskyi_ground(image, self.angle_deg, self.window, self.start_angle_deg)

"""Bogoslavskyi & Stachniss' ground removal (IROS 2016), as their code does it.

Reproduces ``DepthGroundRemover`` of PRBonn/depth_clustering (``src/ground_removal/
depth_ground_remover.cpp``, the version of 2020), step by step:

1. **Depth in-painting** (``RepairDepth(depth, 5, 1.0)``): every empty pixel, visiting each column
   from the top row down and writing in place, takes the mean of all pairs (pixel ``i`` rows above,
   pixel ``j`` rows below, ``1 <= i, j <= 4``) of valid pixels whose ranges differ by less than
   1 m. In-painted pixels count as valid in every later step.
2. **Angle image** (``CreateAngleImage``): at row ``r >= 1`` the inclination
   ``atan2(|dz|, |dx|)`` of the line to the pixel one row *above* (``r - 1``), in float32, with
   an empty pixel counting as the sensor's origin; row 0 is 0. ``np.arctan2`` runs vectorised
   over the whole image (numpy's SIMD loop where the CPU has one); it can differ from the C
   library's scalar ``atan2f``, which their C++ calls, in the last bits (up to 3 units in the
   last place, measured), which moves a decision only for an angle difference within about
   1e-7 rad of the threshold (no pixel changed on 550 frames of the synthetic log and KITTI
   scans when this replaced the scalar call).
3. **Savitzky-Golay smoothing** of every column (``filter2D`` with the quadratic
   ``window``-row kernel, borders reflected without repeating the edge: ``BORDER_REFLECT101``).
4. **Breadth-first growth** (``ZeroOutGroundBFS``): for every column, from its lowest valid
   pixel when that pixel's smoothed angle is at most ``start_angle_deg`` (30 deg, fixed in their
   code) and the pixel is not yet labelled, label every pixel reachable over 4-neighbours (the
   columns wrap around) whose smoothed angle differs from the current pixel's by less than
   ``angle_deg``. Empty pixels are labelled when reached but do not spread the label.
5. **The "dilation"**: their code builds the kernel with ``GetUniformKernel(3, CV_8U)``, which
   writes the float 1.0 with ``at<float>`` into a 3 x 1 *byte* matrix; the bytes that land in the
   matrix are all 0, so the kernel is empty, and ``cv::dilate`` with it moves the label image
   down by one row instead of dilating it (checked with OpenCV 4.6). A pixel is ground when the
   pixel one row above it is labelled; row 0 is never ground.

Steps 2 and 3 run over the whole image (a few vectorised passes), the growth over the pixels it
reaches. The mask returned is over the image's own pixels (in-painted pixels are not points here,
so they are never returned as ground). Measured agreement with their C++ on the synthetic Moosmann
log is in ``results/ground/``.
"""

from __future__ import annotations

import functools
from typing import Annotated, Literal

import numpy as np
from numba import njit
from pydantic import Field
from pydantic.dataclasses import dataclass
from scipy.signal import savgol_coeffs

from flic_cli.component import STRICT
from flic_cli.ground.base import Ground, per_sensor
from flic_cli.range_image import RangeImage

#: Their seeds: a column's lowest pixel starts the growth only below this angle (hard-coded).
START_ANGLE_DEG = 30.0
#: Their in-painting: look this many rows minus one up and down, join ranges closer than this.
REPAIR_STEP = 5
REPAIR_DEPTH_M = 1.0
#: Their "valid depth" test.
_EPS = np.float32(0.001)


@functools.cache
def savgol_kernel(window: int) -> np.ndarray:
    """The quadratic Savitzky-Golay smoothing kernel of ``window`` rows (float32, read-only;
    computed once per window size)."""
    kernel = savgol_coeffs(window, 2).astype(np.float32)
    kernel.setflags(write=False)
    return kernel


@njit(cache=True)
def _repair_depth(ranges: np.ndarray, step: int, threshold: float) -> np.ndarray:
    """Their ``RepairDepth(depth, step, threshold)``: in-paint empty pixels in place, from the top
    row down (in-painted pixels above are used by the pixels below).

    Their loop runs column by column; a pixel depends only on its own column, where the rows
    above are already repaired and the rows below not yet in either order, so sweeping row by row
    (as here, over contiguous memory) gives the same image.
    """
    h, w = ranges.shape
    out = ranges.copy()
    for r in range(h):
        jmax = min(step - 1, h - 1 - r)
        for c in range(w):
            if out[r, c] >= _EPS:
                continue
            has_next = False  # most empty pixels have no valid pixel below (the car's shadow)
            for j in range(1, jmax + 1):
                if out[r + j, c] > _EPS:
                    has_next = True
                    break
            if not has_next:
                continue
            # their sum runs over i (rows above), then j (rows below): the same order here
            total = np.float32(0.0)
            count = 0
            for i in range(1, step):
                if r - i < 0:
                    break
                prev = out[r - i, c]
                if prev <= _EPS:
                    continue
                for j in range(1, jmax + 1):
                    nxt = out[r + j, c]
                    if nxt > _EPS and abs(prev - nxt) < threshold:
                        total += prev + nxt
                        count += 2
            if count > 0:
                out[r, c] = total / np.float32(count)
    return out


@njit(cache=True, inline="always")
def _angle_legs(depth: np.ndarray, sin_p: np.ndarray, cos_p: np.ndarray):
    """The legs ``|dz|``, ``|dx|`` of their ``CreateAngleImage`` at every pixel, float32: row r
    against row r - 1 (above), an empty pixel at the sensor's origin; row 0 is (0, 0), whose
    angle is 0."""
    h, w = depth.shape
    dy = np.zeros((h, w), dtype=np.float32)
    dx = np.zeros((h, w), dtype=np.float32)
    for r in range(1, h):
        cu, su, cd, sd = cos_p[r - 1], sin_p[r - 1], cos_p[r], sin_p[r]
        for c in range(w):
            dx[r, c] = abs(depth[r, c] * cd - depth[r - 1, c] * cu)
            dy[r, c] = abs(depth[r, c] * sd - depth[r - 1, c] * su)
    return dy, dx


@njit(cache=True, inline="always")
def _smooth_columns(angle: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """Savitzky-Golay smoothing of every column (their ``filter2D`` with ``BORDER_REFLECT101``),
    float32, the taps summed in kernel order from 0 (as the lazy version summed them)."""
    h, w = angle.shape
    half = kernel.size // 2
    smooth = np.zeros((h, w), dtype=np.float32)
    for r in range(h):
        for k in range(kernel.size):
            rr = r + k - half
            if h == 1:
                rr = 0
            elif rr < 0:
                rr = -rr
            elif rr > h - 1:
                rr = 2 * (h - 1) - rr
            weight = kernel[k]
            for c in range(w):
                smooth[r, c] += weight * angle[rr, c]
    return smooth


@njit(cache=True, inline="always")
def _grow_and_shift(
    ranges: np.ndarray, depth: np.ndarray, smooth: np.ndarray, threshold: float, start: float
) -> np.ndarray:
    """Their ``ZeroOutGroundBFS`` labelling on the smoothed angles, then the one-row downward
    shift of the labels (their empty "dilation" kernel), over the measured pixels of
    ``ranges`` (in-painted pixels of ``depth`` are not points)."""
    h, w = depth.shape
    label = np.zeros((h, w), dtype=np.bool_)
    stack = np.empty(h * w + 1, dtype=np.int32)
    for c in range(w):
        r = h - 1
        while r > 0 and depth[r, c] < _EPS:
            r -= 1
        if label[r, c] or smooth[r, c] > start:
            continue
        label[r, c] = True
        top = 0
        stack[top] = r * w + c
        top += 1
        while top > 0:
            top -= 1
            i = stack[top]
            pr = i // w
            pc = i - pr * w
            if depth[pr, pc] < _EPS:
                continue  # labelled, but an empty pixel does not spread the label
            a = smooth[pr, pc]
            if pr > 0 and not label[pr - 1, pc] and abs(a - smooth[pr - 1, pc]) < threshold:
                label[pr - 1, pc] = True
                stack[top] = i - w
                top += 1
            if pr < h - 1 and not label[pr + 1, pc] and abs(a - smooth[pr + 1, pc]) < threshold:
                label[pr + 1, pc] = True
                stack[top] = i + w
                top += 1
            nc = pc - 1 if pc > 0 else w - 1
            if not label[pr, nc] and abs(a - smooth[pr, nc]) < threshold:
                label[pr, nc] = True
                stack[top] = pr * w + nc
                top += 1
            nc = pc + 1 if pc < w - 1 else 0
            if not label[pr, nc] and abs(a - smooth[pr, nc]) < threshold:
                label[pr, nc] = True
                stack[top] = pr * w + nc
                top += 1
    ground = np.zeros((h, w), dtype=np.bool_)
    for r in range(1, h):
        for c in range(w):
            ground[r, c] = label[r - 1, c] and ranges[r, c] > 0.0
    return ground


@njit(cache=True)
def _repair_and_legs(ranges: np.ndarray, sin_p: np.ndarray, cos_p: np.ndarray):
    """Steps 1 and the legs of step 2 in one call: (in-painted depth, |dz|, |dx|)."""
    depth = _repair_depth(ranges, REPAIR_STEP, REPAIR_DEPTH_M)
    dy, dx = _angle_legs(depth, sin_p, cos_p)
    return depth, dy, dx


@njit(cache=True)
def _smooth_grow_shift(ranges, depth, angle, kernel, threshold, start):
    """Steps 3 to 5 in one call."""
    return _grow_and_shift(ranges, depth, _smooth_columns(angle, kernel), threshold, start)


@per_sensor
def _row_trig(el: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sine and cosine of their row angles (pitch, positive down), in float32 as their code."""
    pitch = (-el).astype(np.float32)
    return np.sin(pitch), np.cos(pitch)


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
    start_angle_deg: Annotated[float, Field(gt=0, lt=90, description="degrees")] = START_ANGLE_DEG

    def extract(self, image: RangeImage, points: np.ndarray | None = None) -> Ground:
        """The ground pixels of ``image`` (:func:`bogoslavskyi_ground`); every point takes its
        pixel's decision."""
        mask = bogoslavskyi_ground(image, self.angle_deg, self.window, self.start_angle_deg)
        return Ground.from_mask(image, mask)


def bogoslavskyi_ground(
    image: RangeImage,
    angle_deg: float = BogoslavskyiGround.angle_deg,
    window: int = BogoslavskyiGround.window,
    start_angle_deg: float = BogoslavskyiGround.start_angle_deg,
) -> np.ndarray:
    """Ground pixels as Bogoslavskyi & Stachniss' code marks them (see the module docstring).

    Parameters
    ----------
    image : the range image.
    angle_deg : largest difference of smoothed angles between neighbouring ground pixels,
        degrees (9 in their Moosmann example, 7 in their KITTI one).
    window : Savitzky-Golay window, rows (5, 7, 9 or 11, as their code allows).
    start_angle_deg : a column's lowest pixel starts the growth only up to this smoothed angle,
        degrees (30, fixed in their code).

    The defaults are those of :class:`BogoslavskyiGround`.

    Returns
    -------
    (H, W) bool, True = ground; only pixels with a measurement are ground.
    """
    if window not in (5, 7, 9, 11):
        raise ValueError(f"Savitzky-Golay window must be 5, 7, 9 or 11, got {window}")
    ranges = np.ascontiguousarray(image.ranges, dtype=np.float32)
    # |dz| of their angle is the same for either sign of the row angle
    sin_p, cos_p = _row_trig(image.elevation)
    depth, dy, dx = _repair_and_legs(ranges, sin_p, cos_p)
    return _smooth_grow_shift(
        ranges,
        depth,
        np.arctan2(dy, dx, out=dy),
        savgol_kernel(window),
        float(np.float32(np.radians(angle_deg))),
        float(np.radians(start_angle_deg)),
    )

"""Bridge: range-image clustering that reaches over holes and nearer occluders.

FLIC links a measurement to its four direct neighbours only, so an object falls apart wherever a
pixel between two of its measurements holds no return (dark paint, glass, grazing angles) or a
nearer occluder (a pole in front of a car). Bridge links every measurement to the *nearest
linkable measurement* in each direction, walking over empty pixels and over nearer
measurements, and stops where the scan shows free space beside it.

The graph
---------
Nodes: the pixels of ``mask`` with a range ``d > 0`` (a *measurement*). A measurement ``p`` at row
``r``, column ``c``, range ``d_p`` has the *link distance*

    t_p = max(threshold_m, d_p * sin(gamma_deg))

(fixed near the sensor; beyond ``threshold_m / sin(gamma)`` -- 10 m with the defaults -- it
grows with the range like the spacing of the beams, so that sparse far objects stay whole).

A *walk* from ``p`` in direction ``(dr, dc)`` visits ``q_k = (r + k dr, (c + k dc) mod W)`` for
``k = 1 .. K`` (columns wrap around: 360 deg sensor), with ``K = reach_px`` but no further than
the top row (``K <= r`` upwards) and less than a full turn (``K <= W - 1`` sideways):

- ``q_k`` is no node: if it holds a range (a pixel left out by ``mask``, e.g. ground) farther than
  ``d_p``, stop (free space, see below), else go on (a hole);
- ``|p - q_k| < t_p`` (3D distance, the law of cosines with the true angle between the two rays):
  **edge p -- q_k**, stop;
- else ``d_q > d_p``: stop. The ray through ``q_k`` passed the depth of ``p`` without hitting
  anything, so the scan *sees free space* beside ``p`` in that direction: the gap between two
  people or between a car and the wall behind it is not jumped;
- else (``q_k`` is nearer: an occluder in front of ``p``): go on.

Every measurement walks left ``(0, -1)`` and up ``(-1, 0)``. Unless both of these walks ended
with an edge at ``k = 1`` (``p`` lies inside a surface, and its diagonal neighbours are joined
through the adjacent ones), it also walks up-left ``(-1, -1)`` and up-right ``(-1, +1)``. So each
measurement has at most four edges. The clusters are the connected components; those with fewer
than ``min_size`` points (a pixel counts the points that fell into it) are dropped.

A walk also ends as soon as ``d_p sin(alpha_k) >= t_p``, with ``alpha_k`` the angle between the rays
of ``p`` and ``q_k``: every point of that ray is at least ``d_p sin(alpha_k)`` from ``p``, and
``alpha_k`` grows with ``k``, so nothing further on could be linked. This bound changes no edge; it
only keeps the walks short (the window shrinks with the range: at 20 m and 2048 columns a
horizontal walk ends after 11 columns).

With ``reach_px = 1`` and ``gamma_deg = 0`` the graph is FLIC without Map Connections plus the
diagonal links of measurements on a surface's border.
"""

from __future__ import annotations

from typing import Annotated, ClassVar

import numpy as np
from numba import njit
from pydantic import Field
from pydantic.dataclasses import dataclass

from flic_cli.config.component import STRICT
from flic_cli.methods._unionfind import _find, number_components
from flic_cli.methods.base import pixel_weights
from flic_cli.range_image import RangeImage

#: Walk directions (row step, column step): left, up, up-left, up-right (the order of the tables
#: of :func:`walk_tables`). Every walk goes towards earlier pixels in raster order, except left
#: walks across the 360 deg seam.
DIRECTIONS: tuple[tuple[int, int], ...] = ((0, -1), (-1, 0), (-1, -1), (-1, 1))


@njit(cache=True)
def walk_tables(elevation: np.ndarray, width: int, reach: int) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of the angle between the ray of (r, c) and the ray k steps away.

    Parameters
    ----------
    elevation : (H,) row elevations, radians.
    width : W, columns over 360 deg.
    reach : largest step k.

    Returns
    -------
    cos : (4, H, reach + 1) float64, cos of the angle, direction as in :data:`DIRECTIONS`.
    sin : (4, H, reach + 1) float64, the walk's bound: the smallest ``sin(alpha)`` (1 from
        90 deg on) of this and every later step, so that ``d_p * sin[k] >= t_p`` means no step
        from k on can be linked. Steps that leave the image (above row 0) get cos 1, sin 2.
    """
    h = elevation.size
    cos_t = np.ones((4, h, reach + 1))
    sin_t = np.full((4, h, reach + 1), 2.0)
    ce = np.cos(elevation)
    se = np.sin(elevation)
    ck = np.cos(np.arange(reach + 1) * (2.0 * np.pi / width))
    for di in range(4):
        dr = DIRECTIONS[di][0]
        adc = abs(DIRECTIONS[di][1])
        for r in range(h):
            for k in range(1, reach + 1):
                r2 = r + k * dr
                if r2 < 0:
                    break
                # unit vectors (cos e cos a, cos e sin a, sin e): their dot product
                c = ce[r] * ce[r2] * ck[k * adc] + se[r] * se[r2]
                c = min(1.0, max(-1.0, c))
                cos_t[di, r, k] = c
                # every point of a ray at angle alpha from p's ray is at least d_p sin(alpha)
                # from p, or d_p once alpha >= 90 deg
                sin_t[di, r, k] = np.sqrt(1.0 - c * c) if c > 0.0 else 1.0
            # a walk may stop at k only if no later step can link either: suffix minimum (the
            # angle shrinks again past 180 deg on very narrow images)
            for k in range(reach - 1, 0, -1):
                sin_t[di, r, k] = min(sin_t[di, r, k], sin_t[di, r, k + 1])
    return cos_t, sin_t


@njit(cache=True, inline="always")
def _walk(
    rr: np.ndarray,
    raw: np.ndarray,
    w: int,
    r: int,
    c: int,
    d: float,
    tp: float,
    tp2: float,
    j1: int,
    dr: int,
    dc: int,
    kmax: int,
    cos_row: np.ndarray,
    sin_row: np.ndarray,
) -> int:
    """Flat index of the measurement the walk from (r, c) links to, or -1 (module docstring).

    ``rr`` holds the ranges of the nodes (0 elsewhere), ``raw`` every range (a pixel outside the
    mask, e.g. ground, still shows free space). ``j1`` is the flat index of the first step (the
    caller knows it without a modulo).
    """
    if kmax < 1 or d * sin_row[1] >= tp:
        return -1
    dq = np.float64(rr[j1])
    if dq > 0.0:
        if d * d + dq * dq - 2.0 * cos_row[1] * d * dq < tp2:
            return j1
        if dq > d:
            return -1
    elif raw[j1] > d:
        return -1
    for k in range(2, kmax + 1):
        if d * sin_row[k] >= tp:
            return -1
        c2 = c + k * dc
        if c2 < 0:
            c2 += w
        elif c2 >= w:
            c2 -= w
        j = (r + k * dr) * w + c2
        dq = np.float64(rr[j])
        if dq > 0.0:
            if d * d + dq * dq - 2.0 * cos_row[k] * d * dq < tp2:
                return j
            if dq > d:
                return -1
        elif raw[j] > d:
            return -1
    return -1


@njit(cache=True)
def bridge_kernel(
    ranges: np.ndarray,
    mask: np.ndarray,
    elevation: np.ndarray,
    threshold: float,
    sin_gamma: float,
    reach: int,
    min_size: int,
    weights: np.ndarray,
) -> np.ndarray:
    """Connected components of the Bridge graph (module docstring), small ones dropped.

    Parameters
    ----------
    ranges : (H, W) float32, metres, 0 = none.
    mask : (H, W) bool, pixels that take part.
    elevation : (H,) float64, radians.
    threshold : threshold_m, metres.
    sin_gamma : sin(gamma_deg).
    reach : reach_px >= 1.
    min_size : smallest component kept, in summed ``weights``.
    weights : (H, W) int32 points per pixel.

    Returns
    -------
    (H, W) int32 labels, 0 = none, 1..K in raster order of each component's first pixel.
    """
    h, w = ranges.shape
    n = h * w
    raw = ranges.reshape(n)
    mask_flat = mask.reshape(n)
    # the nodes' ranges (0 elsewhere); a plain loop: numba's np.where with a scalar is 20x slower
    rr = np.empty(n, dtype=np.float32)
    for i in range(n):
        rr[i] = raw[i] if mask_flat[i] else np.float32(0.0)
    m_flat = rr > 0
    # Invariant: parent[i] <= i (a root always hangs under the smaller root), so the root of a
    # component is its first pixel in raster order (see number_components). The union steps are
    # written out below: numba compiles a helper that updates `parent` and returns the new root
    # into far slower code.
    parent = np.arange(n, dtype=np.int32)
    cos_t, sin_t = walk_tables(elevation, w, reach)
    k_row = min(reach, w - 1)
    for r in range(h):
        k_up = min(reach, r)
        k_diag = min(k_up, k_row)
        c_l = cos_t[0, r]
        s_l = sin_t[0, r]
        c_u = cos_t[1, r]
        s_u = sin_t[1, r]
        c_ul = cos_t[2, r]
        s_ul = sin_t[2, r]
        c_ur = cos_t[3, r]
        s_ur = sin_t[3, r]
        row = r * w
        for c in range(w):
            i = row + c
            d = np.float64(rr[i])
            if d <= 0.0:
                continue
            tp = max(threshold, d * sin_gamma)
            tp2 = tp * tp
            # The walks go to earlier pixels, except left walks across the seam, which reach the
            # last k_row columns of the row: only there can i already have been joined.
            root = i if c < w - k_row else _find(parent, i)
            j_left = i - 1 if c > 0 else i + w - 1
            j = _walk(rr, raw, w, r, c, d, tp, tp2, j_left, 0, -1, k_row, c_l, s_l)
            inside = j == j_left
            if j >= 0:
                rj = _find(parent, j)
                if rj < root:
                    parent[root] = rj
                    root = rj
                elif rj > root:
                    parent[rj] = root
            if k_up == 0:
                continue
            j_up = i - w
            j = _walk(rr, raw, w, r, c, d, tp, tp2, j_up, -1, 0, k_up, c_u, s_u)
            if j >= 0:
                rj = _find(parent, j)
                if rj < root:
                    parent[root] = rj
                    root = rj
                elif rj > root:
                    parent[rj] = root
            if inside and j == j_up:
                continue
            j1 = j_up - 1 if c > 0 else j_up + w - 1
            j = _walk(rr, raw, w, r, c, d, tp, tp2, j1, -1, -1, k_diag, c_ul, s_ul)
            if j >= 0:
                rj = _find(parent, j)
                if rj < root:
                    parent[root] = rj
                    root = rj
                elif rj > root:
                    parent[rj] = root
            j1 = j_up + 1 if c < w - 1 else j_up - w + 1
            j = _walk(rr, raw, w, r, c, d, tp, tp2, j1, -1, 1, k_diag, c_ur, s_ur)
            if j >= 0:
                rj = _find(parent, j)
                if rj < root:
                    parent[root] = rj
                    root = rj
                elif rj > root:
                    parent[rj] = root
    return number_components(parent, m_flat, weights.reshape(n), min_size).reshape(h, w)


def bridge_labels(
    ranges: np.ndarray,
    elevation: np.ndarray,
    threshold_m: float = 0.35,
    gamma_deg: float = 2.0,
    reach_px: int = 12,
    min_size: int = 100,
    mask: np.ndarray | None = None,
    weights: np.ndarray | None = None,
) -> np.ndarray:
    """Bridge cluster labels of a range image (the graph is defined in the module docstring).

    Parameters
    ----------
    ranges : (H, W) ranges, metres, 0 = no measurement.
    elevation : (H,) row elevations, radians.
    threshold_m : link distance near the sensor, metres.
    gamma_deg : beyond ``threshold_m / sin(gamma)`` the link distance is ``d sin(gamma)``,
        degrees (0 = fixed threshold).
    reach_px : longest walk, pixels (rows or columns).
    min_size : smallest cluster, points (the sum of its pixels' ``weights``).
    mask : (H, W) bool, pixels to cluster (default: all valid pixels).
    weights : (H, W) int, points per pixel (default 1 per pixel).

    Returns
    -------
    (H, W) int32, 0 = unclustered, 1..K clusters numbered in raster order.
    """
    ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    if mask is None:
        mask = ranges > 0
    if reach_px < 1:
        raise ValueError(f"reach_px must be >= 1, got {reach_px}")
    return bridge_kernel(
        ranges,
        np.ascontiguousarray(mask, dtype=np.bool_),
        np.asarray(elevation, dtype=np.float64),
        float(threshold_m),
        float(np.sin(np.radians(gamma_deg))),
        int(reach_px),
        int(min_size),
        pixel_weights(weights, ranges.shape),
    )


@dataclass(frozen=True, config=STRICT)
class Bridge:
    """Bridge as a :class:`flic_cli.methods.base.Method` (see :func:`bridge_labels`).

    Attributes
    ----------
    threshold_m : link distance near the sensor, metres.
    gamma_deg : angle that sets the link distance of far measurements, ``d sin(gamma)``, degrees.
    reach_px : longest walk over holes and occluders, pixels.
    min_size : smallest cluster kept, points of the evaluated set (a pixel counts its points).
    """

    threshold_m: Annotated[float, Field(gt=0, description="link distance near, metres")] = 0.35
    gamma_deg: Annotated[
        float, Field(ge=0, lt=30, description="far link distance d sin(gamma), degrees")
    ] = 2.0
    reach_px: Annotated[int, Field(ge=1, le=256, description="longest walk, pixels")] = 12
    min_size: Annotated[int, Field(ge=1, description="smallest cluster kept, points")] = 100
    main_param: ClassVar[str] = "threshold_m"

    def segment(
        self, image: RangeImage, points: np.ndarray, ground: np.ndarray | None
    ) -> np.ndarray:
        mask = image.ranges > 0 if ground is None else (image.ranges > 0) & ~ground
        labels = bridge_labels(
            image.ranges,
            image.elevation,
            self.threshold_m,
            self.gamma_deg,
            self.reach_px,
            self.min_size,
            mask,
            image.point_counts(),
        )
        return image.point_labels(labels)

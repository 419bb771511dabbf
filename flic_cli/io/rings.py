"""A range image from points whose beam (ring) and column are known (Velodyne, PCD, nuScenes).

Row ``H - 1 - ring`` (ring 0 = the lowest beam, as velodyne-decoder, nebula and nuScenes number
them; row 0 = the top beam), the column given per point (a firing index, or the azimuth binned
over ``W`` columns: :func:`azimuth_columns`); the nearest point of a pixel defines its range, as
in :func:`flic_cli.projection.project_points`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from flic_cli.range_image import RangeImage

_TWO_PI = 2.0 * np.pi


def azimuth_columns(azimuth: np.ndarray, width: int) -> np.ndarray:
    """(N,) int64 column of every azimuth (radians, counter-clockwise from x):
    ``floor((pi - az) / (2 pi) * W) mod W``, the convention of
    :class:`flic_cli.range_image.RangeImage` (column 0 looks backwards)."""
    return _azimuth_columns(np.ascontiguousarray(azimuth, dtype=np.float64), width)


@njit(cache=True)
def _azimuth_columns(az: np.ndarray, width: int) -> np.ndarray:
    out = np.empty(az.size, dtype=np.int64)
    for i in range(az.size):
        c = np.int64(np.floor((np.pi - az[i]) / _TWO_PI * width))
        out[i] = c % width
    return out


def ring_image(
    points: np.ndarray,
    ring: np.ndarray,
    column: np.ndarray,
    width: int,
    elevation: np.ndarray,
) -> RangeImage:
    """Build the range image of points with known rings and columns.

    Parameters
    ----------
    points : (N, 3) float32/float64 xyz in metres (sensor frame), finite, not at the origin.
    ring : (N,) integer beam index, 0 = lowest beam, ``< H``.
    column : (N,) integer column, ``0 <= column < width``.
    width : columns W.
    elevation : (H,) row elevations in radians, row 0 = top (H = ``elevation.size``).

    Returns
    -------
    RangeImage with ``projection == "rings"``: every point has a pixel, the nearest point of a
    pixel gives its range and height (``point_z``), ``counts`` the points per pixel.
    """
    xyz = np.ascontiguousarray(points[:, :3])
    ring = np.ascontiguousarray(ring, dtype=np.int64)
    column = np.ascontiguousarray(column, dtype=np.int64)
    ranges, counts, pix, z = nearest_pixels(
        xyz, ring, column, np.asarray(elevation).size, int(width), 0
    )
    return pixel_image(ranges, counts, pix, z, elevation, int(width))


def pixel_image(
    ranges: np.ndarray,
    counts: np.ndarray,
    pix: np.ndarray,
    z: np.ndarray,
    elevation: np.ndarray,
    width: int,
) -> RangeImage:
    """The RangeImage of :func:`nearest_pixels`' flat arrays (H = ``elevation.size`` rows of
    ``width``): ``projection == "rings"``, every point with a pixel."""
    shape = (int(np.asarray(elevation).size), int(width))
    return RangeImage(
        ranges.reshape(shape),
        np.asarray(elevation, dtype=np.float64),
        pix,
        "rings",
        counts.reshape(shape),
        z.reshape(shape),
        one_point_per_pixel=bool(np.count_nonzero(ranges) == pix.size),
        every_point_has_pixel=True,
    )


@njit(cache=True)
def nearest_pixels(
    xyz: np.ndarray, ring: np.ndarray, column: np.ndarray, h: int, w: int, shift: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Flat (H * W) ranges (m, float32, 0 = none), counts and heights (m) of the points'
    pixels, and (N,) the pixel of every point: row ``h - 1 - ring``, column ``(column +
    shift) mod w`` (``0 <= column < w``); the nearest point of a pixel gives its range."""
    n = xyz.shape[0]
    shift = shift % w
    ranges = np.zeros(h * w, dtype=np.float32)
    counts = np.zeros(h * w, dtype=np.int32)
    z = np.zeros(h * w, dtype=np.float32)
    pix = np.empty(n, dtype=np.int64)
    for i in range(n):
        x = np.float64(xyz[i, 0])
        y = np.float64(xyz[i, 1])
        zz = np.float64(xyz[i, 2])
        r = np.float32(np.sqrt(x * x + y * y + zz * zz))
        c = column[i] + shift
        if c >= w:
            c -= w
        p = (h - 1 - ring[i]) * w + c
        if ranges[p] == 0.0 or r < ranges[p]:
            ranges[p] = r
            z[p] = np.float32(zz)
        counts[p] += 1
        pix[i] = p
    return ranges, counts, pix, z


def ring_elevation(points: np.ndarray, ring: np.ndarray, beams: int) -> np.ndarray:
    """(beams,) median elevation (radians) of every ring's points, row 0 = top ring; a ring
    without points gets the value interpolated from its neighbours (or 0 if none has points)."""
    xyz = np.asarray(points[:, :3], dtype=np.float64)
    el = np.arctan2(xyz[:, 2], np.hypot(xyz[:, 0], xyz[:, 1]))
    med = np.full(beams, np.nan)
    order = np.argsort(ring, kind="stable")
    r_sorted = np.asarray(ring)[order]
    bounds = np.searchsorted(r_sorted, np.arange(beams + 1))
    for b in range(beams):
        if bounds[b + 1] > bounds[b]:
            med[b] = np.median(el[order[bounds[b] : bounds[b + 1]]])
    have = ~np.isnan(med)
    if not have.any():
        return np.zeros(beams)
    med = np.interp(np.arange(beams), np.flatnonzero(have), med[have])
    return med[::-1].copy()  # row 0 = top = highest ring

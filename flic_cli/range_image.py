"""The range image shared by every image-based method.

A :class:`RangeImage` holds, for an ``H x W`` sensor image, the range of every pixel (0 = no
measurement), the elevation of every row and the azimuth of every column, and for every point of
the scan the pixel it fell into. Several points can share a pixel: the nearest one defines the range
there ("owns" the pixel) and every point in the pixel later receives that pixel's cluster id.

Conventions (the same for SemanticKITTI and Moosmann logs):

- row 0 is the top beam; ``elevation[r]`` is the beam's angle above the horizon in radians
  (negative = pointing down);
- column 0 looks backwards (azimuth +pi) and the azimuth decreases to -pi at column ``W - 1``
  (the sensor turns clockwise); the image wraps around horizontally;
- the horizontal angle between adjacent columns is ``2 pi / W``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numba import njit


@dataclass(frozen=True)
class RangeImage:
    """A range image and the map from points to pixels.

    Attributes
    ----------
    ranges : (H, W) float32 array
        Range in metres, 0 where there is no measurement.
    elevation : (H,) float64 array
        Elevation of each row in radians, positive up, row 0 = top beam.
    point_pixel : (N,) int64 array
        Flat pixel index (``row * W + col``) of every point of the scan; -1 for a point that has
        no pixel (outside the vertical field of view of a spherical projection).
    projection : str
        ``"rings"`` (KITTI ring recovery), ``"spherical"`` (KITTI spherical projection) or
        ``"native"`` (the sensor's own image, Moosmann logs).
    """

    ranges: np.ndarray
    elevation: np.ndarray
    point_pixel: np.ndarray
    projection: str

    @property
    def shape(self) -> tuple[int, int]:
        return self.ranges.shape  # type: ignore[return-value]

    @property
    def azimuth(self) -> np.ndarray:
        """(W,) azimuth of each column's centre in radians (+pi at column 0, decreasing)."""
        w = self.ranges.shape[1]
        return np.pi - (np.arange(w) + 0.5) * (2.0 * np.pi / w)

    @property
    def valid(self) -> np.ndarray:
        """(H, W) bool, True where the pixel holds a measurement."""
        return self.ranges > 0

    @property
    def coverage(self) -> float:
        """Share of the scan's points that own a pixel (1.0 = no point hidden by another)."""
        n = self.point_pixel.size
        return float(np.count_nonzero(self.ranges)) / n if n else 0.0

    def heights(self) -> np.ndarray:
        """(H, W) height of every pixel's point relative to the sensor, in metres (z up)."""
        return self.ranges * np.sin(self.elevation).astype(np.float32)[:, None]

    def to_points(self) -> np.ndarray:
        """(H*W, 3) float32 Cartesian point of every pixel (sensor frame: x forward, y left, z up).

        Pixels without a measurement give the origin.
        """
        el = self.elevation[:, None]
        az = self.azimuth[None, :]
        r = self.ranges.astype(np.float64)
        xyz = np.stack(
            [r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el)], axis=-1
        )
        return xyz.reshape(-1, 3).astype(np.float32)

    def point_labels(self, pixel_labels: np.ndarray) -> np.ndarray:
        """Per-point labels from per-pixel labels: every point takes its pixel's label.

        Parameters
        ----------
        pixel_labels : (H, W) integer array, 0 = unclustered.

        Returns
        -------
        (N,) int32 array, 0 for points without a pixel.
        """
        flat = pixel_labels.reshape(-1)
        if self.projection != "spherical":  # every point has a pixel
            return flat.take(self.point_pixel).astype(np.int32, copy=False)
        out = np.zeros(self.point_pixel.size, dtype=np.int32)
        has = self.point_pixel >= 0
        out[has] = flat[self.point_pixel[has]]
        return out


# ---------------------------------------------------------------------------------------------
# SemanticKITTI: ring recovery from the scan order, or a spherical projection.
# ---------------------------------------------------------------------------------------------


def recover_rings(
    points: np.ndarray,
    expected_rows: int = 64,
    min_ring_points: int = 200,
    azimuth: np.ndarray | None = None,
) -> np.ndarray | None:
    """Ring (row) index of every point, recovered from the sensor's scan order.

    The points of a KITTI scan come ring after ring, each ring sweeping counter-clockwise from
    just left of straight ahead through the back seam (+-180 deg) to just right of straight ahead.
    Unwrapping the azimuth along the scan order turns the scan into one spiral whose angle grows by
    2 pi per ring; a ring ends where the unwrapped azimuth passes a multiple of 2 pi. Ego-motion
    compensation makes the azimuth jitter around the seams; unwrapping absorbs the back-seam jitter
    and a running maximum of the ring index absorbs the front-seam jitter.

    Parameters
    ----------
    points : (N, 3+) array in scan order.
    expected_rows : number of rings the sensor has (64 for the HDL-64E).
    min_ring_points : a ring shorter than this is taken as a sign that the scan order is broken.
    azimuth : (N,) ``atan2(y, x)`` of the points, if already computed.

    Returns
    -------
    (N,) int64 ring index in ``0..expected_rows-1`` (0 = top beam), or None when the scan does
    not look like ``expected_rows`` rings in scan order (the caller then falls back to a
    spherical projection).
    """
    if points.shape[0] == 0:
        return None
    if azimuth is None:
        azimuth = np.arctan2(points[:, 1].astype(np.float64), points[:, 0].astype(np.float64))
    spiral = np.unwrap(azimuth)
    spiral -= 2.0 * np.pi * np.floor(spiral[: min(50, spiral.size)].min() / (2.0 * np.pi))
    ring = np.maximum.accumulate(np.floor(spiral / (2.0 * np.pi)).astype(np.int64))
    ring -= ring[0]
    counts = np.bincount(ring)
    if counts.size != expected_rows or counts.min() < min_ring_points:
        return None
    return ring


def _row_elevation(elev_pts: np.ndarray, rows: np.ndarray, n_rows: int) -> np.ndarray:
    """Median elevation of the points of every row; rows without points are interpolated.

    ``rows`` must be non-decreasing (ring indices in scan order).
    """
    bounds = np.searchsorted(rows, np.arange(n_rows + 1))
    out = np.full(n_rows, np.nan)
    for r in range(n_rows):
        if bounds[r + 1] > bounds[r]:
            out[r] = np.median(elev_pts[bounds[r] : bounds[r + 1]])
    ok = np.isfinite(out)
    if not ok.any():
        return np.linspace(np.radians(3.0), np.radians(-25.0), n_rows)
    idx = np.arange(n_rows)
    return np.interp(idx, idx[ok], out[ok])


@njit(cache=True)
def _nearest_per_pixel(rng: np.ndarray, pix: np.ndarray, n_pixels: int) -> np.ndarray:
    ranges = np.zeros(n_pixels, dtype=np.float32)
    for i in range(pix.size):
        p = pix[i]
        if ranges[p] == 0.0 or rng[i] < ranges[p]:
            ranges[p] = rng[i]
    return ranges


def _fill_pixels(
    rng: np.ndarray, rows: np.ndarray, cols: np.ndarray, n_rows: int, width: int
) -> tuple[np.ndarray, np.ndarray]:
    """Range image where the nearest point of each pixel wins; flat pixel index per point."""
    pix = rows * width + cols
    ranges = _nearest_per_pixel(rng.astype(np.float32), pix, n_rows * width)
    return ranges.reshape(n_rows, width), pix


def project_points(
    points: np.ndarray,
    width: int = 2048,
    mode: str = "rings",
    rows: int = 64,
    fov_up_deg: float = 3.0,
    fov_down_deg: float = -25.0,
    keep: np.ndarray | None = None,
) -> RangeImage:
    """Project a scan (in sensor scan order) into a range image.

    Parameters
    ----------
    points : (N, 3+) float array, metres, sensor frame.
    width : number of columns (azimuth bins over 360 deg).
    mode : ``"rings"`` recovers the rows from the scan order (falls back to ``"spherical"`` with a
        warning when that fails); ``"spherical"`` bins the elevation uniformly over the vertical
        field of view ``[fov_down_deg, fov_up_deg]``.
    rows : number of rows (beams).
    keep : (N,) bool, the points that go into the image (e.g. all but the ground classes). Rows
        are recovered from the whole scan, so removing points does not break the ring recovery.

    Returns
    -------
    RangeImage
        Over the kept points: ``point_pixel`` has one entry per kept point.
    """
    if mode not in ("rings", "spherical"):
        raise ValueError(f"unknown projection mode {mode!r} (rings | spherical)")
    xyz = np.asarray(points[:, :3], dtype=np.float64)
    rng = np.sqrt(np.einsum("ij,ij->i", xyz, xyz))
    az = np.arctan2(xyz[:, 1], xyz[:, 0])
    cols = np.floor((np.pi - az) / (2.0 * np.pi) * width).astype(np.int64) % width
    with np.errstate(invalid="ignore", divide="ignore"):
        elev = np.arcsin(np.clip(xyz[:, 2] / np.maximum(rng, 1e-9), -1.0, 1.0))
    ring = recover_rings(xyz, rows, azimuth=az) if mode == "rings" else None
    if mode == "rings" and ring is None:
        warnings.warn(
            f"ring recovery did not find {rows} rings in scan order; "
            "using a spherical projection for this scan",
            stacklevel=2,
        )
    if ring is not None:
        elevation = _row_elevation(elev, ring, rows)
        if keep is not None:
            rng, ring, cols = rng[keep], ring[keep], cols[keep]
        ranges, pix = _fill_pixels(rng.astype(np.float32), ring, cols, rows, width)
        return RangeImage(ranges, elevation, pix, "rings")
    if keep is not None:
        rng, elev, cols = rng[keep], elev[keep], cols[keep]
    up, down = np.radians(fov_up_deg), np.radians(fov_down_deg)
    r_idx = np.floor((up - elev) / (up - down) * rows).astype(np.int64)
    inside = (r_idx >= 0) & (r_idx < rows) & (rng > 0)
    elevation = up - (np.arange(rows) + 0.5) * (up - down) / rows
    ranges, pix_in = _fill_pixels(
        rng[inside].astype(np.float32), r_idx[inside], cols[inside], rows, width
    )
    pix = np.full(rng.shape[0], -1, dtype=np.int64)
    pix[inside] = pix_in
    return RangeImage(ranges, elevation, pix, "spherical")


def from_sensor_image(ranges: np.ndarray, elevation: np.ndarray) -> RangeImage:
    """Wrap a sensor's own range image (Moosmann logs): every valid pixel is one point.

    Parameters
    ----------
    ranges : (H, W) float32 array, metres, 0 = no measurement.
    elevation : (H,) row elevations in radians, positive up, row 0 = top.
    """
    ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    pix = np.flatnonzero(ranges.reshape(-1) > 0).astype(np.int64)
    return RangeImage(ranges, np.asarray(elevation, dtype=np.float64), pix, "native")

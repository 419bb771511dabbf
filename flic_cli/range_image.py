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

from dataclasses import dataclass, field

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
    counts : (H, W) int32 array or None
        Number of points that fell into each pixel, when the projection counted them (it does,
        at no extra cost); use :meth:`point_counts`, which counts when this is None.
    point_z : (H, W) float32 array or None
        Height (z, metres) of every pixel's nearest point, 0 where empty, when the image was
        projected from points (the projection keeps it at no extra cost); None for a sensor's
        own image, whose pixels lie on their row's elevation. A projected pixel's point is not:
        its row's elevation is a median over the beam (rings) or the middle of a bin
        (spherical). See :meth:`heights`.
    attached : (K, 3) int64 array or None
        Held pixels, set by a ground step (step 8 of
        :class:`flic_cli.ground.column.ColumnGround`): per row a held pixel, the pixel standing
        on it whose cluster its points take (-1: none) and its number of points. The
        clusterers leave held pixels out (they link nothing) and count their points towards
        the cluster they take.
    """

    ranges: np.ndarray
    elevation: np.ndarray
    point_pixel: np.ndarray
    projection: str
    counts: np.ndarray | None = field(default=None, repr=False, compare=False)
    point_z: np.ndarray | None = field(default=None, repr=False, compare=False)
    attached: np.ndarray | None = field(default=None, repr=False, compare=False)

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

    def point_counts(self) -> np.ndarray:
        """(H, W) int32 number of the scan's points in every pixel (0 = empty pixel).

        A pixel's range comes from its nearest point; this counts all of them (e.g. for minimum
        cluster sizes counted in points rather than pixels).
        """
        if self.counts is not None:
            return self.counts
        pix = self.point_pixel
        if self.projection == "spherical":
            pix = pix[pix >= 0]
        return np.bincount(pix, minlength=self.ranges.size).astype(np.int32).reshape(self.shape)

    def heights(self) -> np.ndarray:
        """(H, W) float32 height of every pixel's point relative to the sensor, in metres (z up);
        0 where empty: ``point_z`` where the image knows it (projected scans), else the pixel's
        range along its row's elevation."""
        if self.point_z is not None:
            return self.point_z
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

    def pixel_points(self, pixels: np.ndarray | None = None) -> np.ndarray:
        """(M, 3) float32 Cartesian points of some pixels, equal to ``to_points()[pixels]``.

        Parameters
        ----------
        pixels : (M,) flat pixel indices; default ``point_pixel`` (for a sensor image: the scan's
            points, one per valid pixel).
        """
        pix = self.point_pixel if pixels is None else np.asarray(pixels, dtype=np.int64)
        el = self.elevation
        az = self.azimuth
        return _pixel_points(
            self.ranges.reshape(-1), pix, self.ranges.shape[1],
            np.cos(el), np.sin(el), np.cos(az), np.sin(az),
        )  # fmt: skip

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


@njit(cache=True)
def _pixel_points(
    ranges: np.ndarray,
    pix: np.ndarray,
    width: int,
    cos_el: np.ndarray,
    sin_el: np.ndarray,
    cos_az: np.ndarray,
    sin_az: np.ndarray,
) -> np.ndarray:
    """Points of the pixels ``pix`` of a flat range image, computed as :meth:`RangeImage.to_points`
    does (float64, the same products in the same order, then float32)."""
    out = np.empty((pix.size, 3), dtype=np.float32)
    for j in range(pix.size):
        p = pix[j]
        row = p // width
        col = p - row * width
        r = np.float64(ranges[p])
        out[j, 0] = np.float32(r * cos_el[row] * cos_az[col])
        out[j, 1] = np.float32(r * cos_el[row] * sin_az[col])
        out[j, 2] = np.float32(r * sin_el[row])
    return out


def from_sensor_image(ranges: np.ndarray, elevation: np.ndarray) -> RangeImage:
    """Wrap a sensor's own range image (Moosmann logs): every valid pixel is one point.

    Parameters
    ----------
    ranges : (H, W) float32 array, metres, 0 = no measurement.
    elevation : (H,) row elevations in radians, positive up, row 0 = top.
    """
    return _from_sensor_image(ranges, elevation, False)[0]


def from_sensor_image_with_points(
    ranges: np.ndarray, elevation: np.ndarray
) -> tuple[RangeImage, np.ndarray]:
    """:func:`from_sensor_image` and the scan's points in one pass over the image.

    Returns
    -------
    image : RangeImage
    points : (N, 3) float32 Cartesian point of every valid pixel, in the order of
        ``image.point_pixel`` (row-major), equal to ``image.to_points()[image.point_pixel]``.
    """
    image, points = _from_sensor_image(ranges, elevation, True)
    assert points is not None
    return image, points


def _from_sensor_image(
    ranges: np.ndarray, elevation: np.ndarray, with_points: bool
) -> tuple[RangeImage, np.ndarray | None]:
    ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    elevation = np.asarray(elevation, dtype=np.float64)
    pix, counts = _sensor_pixels(ranges)
    image = RangeImage(ranges, elevation, pix, "native", counts)
    if not with_points:
        return image, None
    az = image.azimuth
    points = _sensor_points(
        ranges, np.cos(elevation), np.sin(elevation), np.cos(az), np.sin(az), pix.size
    )
    return image, points


@njit(cache=True)
def _sensor_pixels(ranges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Valid pixels of an (H, W) image (row-major flat indices) and points per pixel (0 or 1)."""
    h, w = ranges.shape
    n = 0
    for row in range(h):
        for col in range(w):
            n += ranges[row, col] > 0
    pix = np.empty(n, dtype=np.int64)
    counts = np.zeros((h, w), dtype=np.int32)
    j = 0
    for row in range(h):
        for col in range(w):
            if ranges[row, col] > 0:
                pix[j] = row * w + col
                counts[row, col] = 1
                j += 1
    return pix, counts


@njit(cache=True)
def _sensor_points(
    ranges: np.ndarray,
    cos_el: np.ndarray,
    sin_el: np.ndarray,
    cos_az: np.ndarray,
    sin_az: np.ndarray,
    n: int,
) -> np.ndarray:
    """(n, 3) float32 points of the ``n`` valid pixels of an (H, W) image in row-major order,
    computed as :func:`_pixel_points` does."""
    h, w = ranges.shape
    out = np.empty(3 * n, dtype=np.float32)
    j = 0
    for row in range(h):
        ce = cos_el[row]
        se = sin_el[row]
        for col in range(w):
            rf = ranges[row, col]
            if rf > 0:
                r = np.float64(rf)
                out[3 * j] = np.float32(r * ce * cos_az[col])
                out[3 * j + 1] = np.float32(r * ce * sin_az[col])
                out[3 * j + 2] = np.float32(r * se)
                j += 1
    return out.reshape(n, 3)

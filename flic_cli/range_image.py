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

from dataclasses import InitVar, dataclass, field

import numpy as np
from numba import njit


@dataclass(frozen=True)
class RangeImage:
    """A range image, the sensor geometry of its pixels and the map from points to pixels.

    Attributes
    ----------
    ranges : (H, W) float32 array
        Range in metres, 0 where there is no measurement.
    elevation : (H,) float64 array
        Elevation of each row in radians, positive up, row 0 = top beam.
    point_pixel : (N,) int64 array
        Flat pixel index (``row * W + col``) of every point of the scan; -1 for a point that has
        no pixel (outside the vertical field of view of a spherical projection, or left out of
        its pixel by a ground step, :func:`flic_cli.ground.base.leave_pixels`).
    projection : str
        Display name of how the image was made: ``"rings"`` (KITTI ring recovery),
        ``"spherical"`` (KITTI spherical projection) or ``"native"`` (a sensor's own image).
        Nothing branches on it: what the methods need is in the typed fields below.
    counts : (H, W) int32 array or None, init only
        Number of points in every pixel, given by whoever made ``point_pixel`` when it counted
        them in the same pass (the projection kernels do); otherwise derived from
        ``point_pixel`` on first use. Read it with :meth:`point_counts`; never stored by
        callers (``dataclasses.replace`` with a new ``point_pixel`` derives it anew).
    point_z : (H, W) float32 array or None
        Height (z, metres) of every pixel's nearest point, 0 where empty, when the image was
        projected from points (the projection keeps it at no extra cost); None for a sensor's
        own image, whose pixels lie on their row's elevation. A projected pixel's point is not:
        its row's elevation is a median over the beam (rings) or the middle of a bin
        (spherical). See :meth:`heights`.
    azimuth_offset : (H,) float64 array
        Azimuth offset of every row in radians, added to the column's centre (see
        :meth:`pixel_azimuth`): a sensor whose beams do not fire at one azimuth (Ouster's
        ``beam_azimuth_angles``). Default (None): zeros.
    one_point_per_pixel : bool
        Every valid pixel holds exactly one point and no point shares a pixel (a sensor's own
        image): the methods need not read the counts.
    every_point_has_pixel : bool
        No entry of ``point_pixel`` is -1 (ring recovery, a sensor's own image; not a spherical
        projection, whose field of view may miss points).
    """

    ranges: np.ndarray
    elevation: np.ndarray
    point_pixel: np.ndarray
    projection: str = "native"
    counts: InitVar[np.ndarray | None] = None
    point_z: np.ndarray | None = field(default=None, repr=False, compare=False)
    azimuth_offset: np.ndarray | None = field(default=None, repr=False, compare=False)
    one_point_per_pixel: bool = False
    every_point_has_pixel: bool = True

    def __post_init__(self, counts: np.ndarray | None) -> None:
        h = self.ranges.shape[0]
        if self.azimuth_offset is None:
            object.__setattr__(self, "azimuth_offset", np.zeros(h))
        else:
            offset = np.ascontiguousarray(self.azimuth_offset, dtype=np.float64)
            if offset.shape != (h,):
                raise ValueError(f"azimuth_offset has shape {offset.shape}, the image {h} rows")
            object.__setattr__(self, "azimuth_offset", offset)
        if counts is not None and counts.shape != self.ranges.shape:
            raise ValueError(f"counts have shape {counts.shape}, the image {self.ranges.shape}")
        object.__setattr__(self, "_counts", counts)

    @property
    def shape(self) -> tuple[int, int]:
        return self.ranges.shape  # type: ignore[return-value]

    @property
    def azimuth(self) -> np.ndarray:
        """(W,) azimuth of each column's centre in radians (+pi at column 0, decreasing)."""
        w = self.ranges.shape[1]
        return np.pi - (np.arange(w) + 0.5) * (2.0 * np.pi / w)

    @property
    def has_azimuth_offset(self) -> bool:
        """Whether any row's azimuth is offset from its column's centre."""
        return bool(np.any(self.azimuth_offset))

    def pixel_azimuth(self) -> np.ndarray:
        """(H, W) azimuth of every pixel in radians: its column's centre plus its row's
        offset."""
        return self.azimuth[None, :] + self.azimuth_offset[:, None]

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
        counts = self._counts  # type: ignore[attr-defined]
        if counts is None:
            pix = self.point_pixel
            if not self.every_point_has_pixel:
                pix = pix[pix >= 0]
            counts = np.bincount(pix, minlength=self.ranges.size).astype(np.int32)
            counts = counts.reshape(self.shape)
            object.__setattr__(self, "_counts", counts)
        return counts

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
        az = self.pixel_azimuth() if self.has_azimuth_offset else self.azimuth[None, :]
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
        cos_az, sin_az, per_row = _azimuth_tables(self)
        return _pixel_points(
            self.ranges.reshape(-1), pix, self.ranges.shape[1],
            np.cos(el), np.sin(el), cos_az, sin_az, per_row,
        )  # fmt: skip

    def pixel_values(self, point_values: np.ndarray, fill: int = 0) -> np.ndarray:
        """Per-pixel values from per-point values, the inverse of :meth:`point_labels`: each
        pixel takes the value of the last point that falls into it.

        Parameters
        ----------
        point_values : (N,) array, one value per point.
        fill : the value of pixels that no point falls into.

        Returns
        -------
        (H, W) array of ``point_values``' dtype.
        """
        values = np.asarray(point_values)
        out = np.full(self.ranges.size, fill, dtype=values.dtype)
        has = self.point_pixel >= 0
        out[self.point_pixel[has]] = values[has]
        return out.reshape(self.ranges.shape)

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
        if self.every_point_has_pixel:
            return flat.take(self.point_pixel).astype(np.int32, copy=False)
        out = np.zeros(self.point_pixel.size, dtype=np.int32)
        has = self.point_pixel >= 0
        out[has] = flat[self.point_pixel[has]]
        return out


def _azimuth_tables(image: RangeImage) -> tuple[np.ndarray, np.ndarray, int]:
    """cos and sin of the azimuth as the point kernels read them: (1, W) of the column centres
    and row stride 0 without row offsets, else (H, W) of every pixel and row stride 1."""
    if image.has_azimuth_offset:
        az = image.pixel_azimuth()
        return np.cos(az), np.sin(az), 1
    az = image.azimuth[None, :]
    return np.cos(az), np.sin(az), 0


@njit(cache=True)
def _pixel_points(
    ranges: np.ndarray,
    pix: np.ndarray,
    width: int,
    cos_el: np.ndarray,
    sin_el: np.ndarray,
    cos_az: np.ndarray,
    sin_az: np.ndarray,
    per_row: int,
) -> np.ndarray:
    """Points of the pixels ``pix`` of a flat range image, computed as :meth:`RangeImage.to_points`
    does (float64, the same products in the same order, then float32); the azimuth of (row,
    col) is read at ``cos_az[row * per_row, col]`` (:func:`_azimuth_tables`)."""
    out = np.empty((pix.size, 3), dtype=np.float32)
    for j in range(pix.size):
        p = pix[j]
        row = p // width
        col = p - row * width
        ar = row * per_row
        r = np.float64(ranges[p])
        out[j, 0] = np.float32(r * cos_el[row] * cos_az[ar, col])
        out[j, 1] = np.float32(r * cos_el[row] * sin_az[ar, col])
        out[j, 2] = np.float32(r * sin_el[row])
    return out


def from_sensor_image(
    ranges: np.ndarray, elevation: np.ndarray, azimuth_offset: np.ndarray | None = None
) -> RangeImage:
    """Wrap a sensor's own range image (Moosmann logs, sensor readers): every valid pixel is one
    point.

    Parameters
    ----------
    ranges : (H, W) float32 array, metres, 0 = no measurement.
    elevation : (H,) row elevations in radians, positive up, row 0 = top.
    azimuth_offset : (H,) azimuth offset of every row in radians, added to the column's centre
        (e.g. Ouster's ``beam_azimuth_angles``); default zeros.
    """
    return _from_sensor_image(ranges, elevation, azimuth_offset, False)[0]


def from_sensor_image_with_points(
    ranges: np.ndarray, elevation: np.ndarray, azimuth_offset: np.ndarray | None = None
) -> tuple[RangeImage, np.ndarray]:
    """:func:`from_sensor_image` and the scan's points in one pass over the image.

    Returns
    -------
    image : RangeImage
    points : (N, 3) float32 Cartesian point of every valid pixel, in the order of
        ``image.point_pixel`` (row-major), equal to ``image.to_points()[image.point_pixel]``.
    """
    image, points = _from_sensor_image(ranges, elevation, azimuth_offset, True)
    assert points is not None
    return image, points


def _from_sensor_image(
    ranges: np.ndarray,
    elevation: np.ndarray,
    azimuth_offset: np.ndarray | None,
    with_points: bool,
) -> tuple[RangeImage, np.ndarray | None]:
    ranges = np.ascontiguousarray(ranges, dtype=np.float32)
    elevation = np.asarray(elevation, dtype=np.float64)
    pix, counts = _sensor_pixels(ranges)
    image = RangeImage(
        ranges, elevation, pix, "native", counts, azimuth_offset=azimuth_offset,
        one_point_per_pixel=True, every_point_has_pixel=True,
    )  # fmt: skip
    if not with_points:
        return image, None
    cos_az, sin_az, per_row = _azimuth_tables(image)
    points = _sensor_points(
        ranges, np.cos(elevation), np.sin(elevation), cos_az, sin_az, per_row, pix.size
    )
    return image, points


def sensor_subset(image: RangeImage, keep: np.ndarray) -> RangeImage:
    """A sensor's own image (:attr:`RangeImage.one_point_per_pixel`) with only the points
    ``keep`` (the other pixels emptied); its geometry is kept.

    Parameters
    ----------
    image : the image of a sensor, one point per valid pixel.
    keep : (N,) bool over ``image.point_pixel``.
    """
    pix = image.point_pixel[keep]
    ranges = np.zeros(image.ranges.size, dtype=np.float32)
    ranges[pix] = image.ranges.reshape(-1)[pix]
    return RangeImage(
        ranges.reshape(image.ranges.shape), image.elevation, pix, image.projection,
        azimuth_offset=image.azimuth_offset, one_point_per_pixel=image.one_point_per_pixel,
        every_point_has_pixel=image.every_point_has_pixel,
    )  # fmt: skip


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
    per_row: int,
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
        ca = cos_az[row * per_row]
        sa = sin_az[row * per_row]
        for col in range(w):
            rf = ranges[row, col]
            if rf > 0:
                r = np.float64(rf)
                out[3 * j] = np.float32(r * ce * ca[col])
                out[3 * j + 1] = np.float32(r * ce * sa[col])
                out[3 * j + 2] = np.float32(r * se)
                j += 1
    return out.reshape(n, 3)

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
    """

    ranges: np.ndarray
    elevation: np.ndarray
    point_pixel: np.ndarray
    projection: str
    counts: np.ndarray | None = field(default=None, repr=False, compare=False)

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


# ---------------------------------------------------------------------------------------------
# SemanticKITTI: ring recovery from the scan order, or a spherical projection.
#
# The numba kernels below do in one pass what used to take a dozen numpy passes, and give the
# same numbers bit for bit: the azimuth and the elevation's arcsin still come from numpy's
# vectorised ufuncs (numba's libm atan2/asin differ from them in the last bit), and every other
# operation is the one numpy performed, in the same order (np.unwrap's correction and cumulative
# sum, the range as sqrt((x*x + z*z) + y*y), the association that numpy's SIMD einsum used).
# ---------------------------------------------------------------------------------------------

_TWO_PI = 2.0 * np.pi


@njit(cache=True)
def _unwrap_step(a: float, prev: float, cum: float) -> float:
    """``np.unwrap``'s running correction after azimuth ``a`` (previous azimuth ``prev``)."""
    dd = a - prev
    if abs(dd) < np.pi:  # below the discontinuity: no correction (np.unwrap adds 0)
        return cum + 0.0
    ddmod = (dd - (-np.pi)) % _TWO_PI + (-np.pi)
    if ddmod == -np.pi and dd > 0:
        ddmod = np.pi
    return cum + (ddmod - dd)


@njit(cache=True)
def _spiral_offset(az: np.ndarray) -> float:
    """Multiple of 2 pi that moves the start of the unwrapped azimuth into ``[0, 2 pi)``."""
    m = az[0]
    cum = 0.0
    for i in range(1, min(50, az.size)):
        cum = _unwrap_step(az[i], az[i - 1], cum)
        s = az[i] + cum
        if s < m:
            m = s
    return _TWO_PI * np.floor(m / _TWO_PI)


@njit(cache=True)
def _ring_starts(az: np.ndarray, expected_rows: int) -> tuple[np.ndarray, bool]:
    """Where every ring starts, from the azimuths in scan order (see :func:`recover_rings`).

    Returns
    -------
    starts : (expected_rows + 1,) int64, ``starts[r]`` = index of the first point of ring ``r``
        or later (the ring index never decreases along the scan), ``starts[-1] = N``
    ok : False when the ring index reached ``expected_rows`` (``starts`` is then incomplete)
    """
    n = az.size
    starts = np.zeros(expected_rows + 1, dtype=np.int64)
    offset = _spiral_offset(az)
    cum = 0.0
    top = first = np.int64(np.floor((az[0] - offset) / _TWO_PI))
    current = 0
    for i in range(1, n):
        cum = _unwrap_step(az[i], az[i - 1], cum)
        k = np.int64(np.floor((az[i] + cum - offset) / _TWO_PI))
        if k > top:
            top = k
            r = top - first
            if r >= expected_rows:
                return starts, False
            for q in range(current + 1, r + 1):
                starts[q] = i
            current = r
    for q in range(current + 1, expected_rows + 1):
        starts[q] = n
    return starts, True


def _ring_counts(az: np.ndarray, expected_rows: int, min_ring_points: int) -> np.ndarray | None:
    """Points per ring (rings are consecutive in scan order), or None when the scan is not
    ``expected_rows`` rings of at least ``min_ring_points`` points."""
    if az.size == 0:
        return None
    starts, ok = _ring_starts(az, expected_rows)
    if not ok:
        return None
    counts = np.diff(starts)
    if counts[-1] == 0 or counts.min() < min_ring_points:
        return None
    return counts


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
    points : (N, 3+) array in scan order, finite coordinates.
    expected_rows : number of rings the sensor has (64 for the HDL-64E).
    min_ring_points : a ring shorter than this is taken as a sign that the scan order is broken.
    azimuth : (N,) ``atan2(y, x)`` of the points in radians, if already computed.

    Returns
    -------
    (N,) int64 ring index in ``0..expected_rows-1`` (0 = top beam), or None when the scan does
    not look like ``expected_rows`` rings in scan order (the caller then falls back to a
    spherical projection).
    """
    if azimuth is None:
        azimuth = np.arctan2(points[:, 1], points[:, 0], dtype=np.float64)
    az = np.ascontiguousarray(azimuth, dtype=np.float64)
    counts = _ring_counts(az, expected_rows, min_ring_points)
    return None if counts is None else np.repeat(np.arange(expected_rows), counts)


@njit(cache=True)
def _range(flat: np.ndarray, i: int) -> float:
    """Range of point ``i`` of ``(3N,)`` xyz in metres, float64.

    Summed as numpy's SIMD ``einsum("ij,ij->i")`` (AVX2 / AVX-512) did before,
    ``sqrt((x^2 + z^2) + y^2)``, so that the values are bit-identical to the earlier numpy code.
    """
    x = np.float64(flat[3 * i])
    y = np.float64(flat[3 * i + 1])
    z = np.float64(flat[3 * i + 2])
    return np.sqrt((x * x + z * z) + y * y)


@njit(cache=True)
def _point_geometry(
    flat: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """x, y (float64), range (float32) and sine of the elevation of every point of ``(3N,)`` xyz.

    The sine is ``clip(z / max(range, 1e-9), -1, 1)`` as before. (A flat array, not an (N, 3)
    one, lets LLVM vectorise the loop.)
    """
    x64 = np.empty(n, dtype=np.float64)
    y64 = np.empty(n, dtype=np.float64)
    rng = np.empty(n, dtype=np.float32)
    sin_elev = np.empty(n, dtype=np.float64)
    for i in range(n):
        x64[i] = np.float64(flat[3 * i])
        y64[i] = np.float64(flat[3 * i + 1])
        r = _range(flat, i)
        rng[i] = np.float32(r)
        v = np.float64(flat[3 * i + 2]) / (r if r > 1e-9 else 1e-9)
        v = v if v > -1.0 else -1.0
        sin_elev[i] = v if v < 1.0 else 1.0
    return x64, y64, rng, sin_elev


@njit(cache=True)
def _ring_pixels(
    rng: np.ndarray,
    az: np.ndarray,
    ring_counts: np.ndarray,
    keep: np.ndarray,
    use_keep: bool,
    width: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nearest-point range image, points per pixel and pixel of every kept point (``rng``: the
    points' ranges in metres).

    The rows are the rings (consecutive in scan order, ``ring_counts`` points each); the column
    is ``floor((pi - az) / (2 pi) * width) mod width``, the pixel ``row * width + column``.
    """
    n = az.size
    rows = ring_counts.size
    pix = np.empty(n, dtype=np.int64)
    for i in range(n):  # columns (vectorised)
        c = np.int64(np.floor((np.pi - az[i]) / _TWO_PI * width))
        if c >= width or c < 0:
            c %= width
        pix[i] = c
    ranges = np.zeros(rows * width, dtype=np.float32)
    counts = np.zeros(rows * width, dtype=np.int32)
    j = 0
    start = 0
    for row in range(rows):
        base = row * width
        stop = start + ring_counts[row]
        for i in range(start, stop):
            if use_keep and not keep[i]:
                continue
            p = base + pix[i]
            r = rng[i]
            if ranges[p] == 0.0 or r < ranges[p]:
                ranges[p] = r
            counts[p] += 1
            pix[j] = p
            j += 1
        start = stop
    return ranges, counts, pix[:j]


@njit(cache=True)
def _select(buf: np.ndarray, lo: int, hi: int, k: int) -> float:
    """The k-th smallest of ``buf[lo:hi]`` (quickselect; reorders ``buf[lo:hi]``)."""
    hi -= 1
    while hi > lo:
        mid = (lo + hi) >> 1
        # median of three as the pivot, moved to buf[hi]
        if buf[mid] < buf[lo]:
            buf[mid], buf[lo] = buf[lo], buf[mid]
        if buf[hi] < buf[lo]:
            buf[hi], buf[lo] = buf[lo], buf[hi]
        if buf[mid] < buf[hi]:
            buf[mid], buf[hi] = buf[hi], buf[mid]
        pivot = buf[hi]
        i = lo
        for t in range(lo, hi):
            if buf[t] < pivot:
                buf[t], buf[i] = buf[i], buf[t]
                i += 1
        buf[i], buf[hi] = buf[hi], buf[i]
        if i == k:
            return buf[i]
        if k < i:
            hi = i - 1
        else:
            lo = i + 1
    return buf[lo]


@njit(cache=True)
def _max_below(values: np.ndarray, lo: int, hi: int, limit: float) -> float:
    """Largest of ``values[lo:hi]`` below ``limit`` (-inf when none is)."""
    out = -np.inf
    for q in range(lo, hi):
        v = values[q]
        if v < limit and v > out:
            out = v
    return out


@njit(cache=True)
def _median(values: np.ndarray, start: int, stop: int, buf: np.ndarray) -> float:
    """``np.median(values[start:stop])`` of finite values, exactly (reorders the segment).

    np.median is the middle value, or the mean of the two middle values. Both are found by a
    quickselect; on a long segment, first narrow it down: a sorted sample of 31 values gives a
    band ``[a, b]`` around the middle, one branch-free pass counts the values below ``a`` and copies
    those inside the band to ``buf``, and when the middle ranks fall inside the band only the band
    (a few per cent of the segment) is searched. Otherwise (or on a short segment) the whole
    segment is.
    """
    n = stop - start
    k = n // 2  # rank of the upper middle value; the lower one has rank k - 1 when n is even
    even = n % 2 == 0
    if n >= 512:
        m = 31
        sample = np.empty(m)
        step = n // m
        for q in range(m):  # insertion sort of an evenly spread sample
            v = values[start + q * step]
            j = q
            while j > 0 and sample[j - 1] > v:
                sample[j] = sample[j - 1]
                j -= 1
            sample[j] = v
        pos = k * m // n
        a = sample[max(pos - 3, 0)]
        b = sample[min(pos + 3, m - 1)]
        below = 0
        inside = 0
        for q in range(start, stop):
            v = values[q]
            below += v < a
            buf[inside] = v
            inside += (v >= a) & (v <= b)
        if below <= k < below + inside:
            kk = k - below
            upper = _select(buf, 0, inside, kk)  # leaves buf[:kk] <= upper
            if not even:
                return upper
            if kk > 0:
                lower = buf[0]
                for q in range(1, kk):
                    if buf[q] > lower:
                        lower = buf[q]
            else:  # the lower middle value is the largest one below the band
                lower = _max_below(values, start, stop, a)
            return (lower + upper) / 2.0
    upper = _select(values, start, stop, start + k)  # leaves values[start:start + k] <= upper
    if not even:
        return upper
    lower = values[start]
    for q in range(start + 1, start + k):
        if values[q] > lower:
            lower = values[q]
    return (lower + upper) / 2.0


@njit(cache=True)
def _segment_medians(values: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """``np.median`` of each consecutive segment of finite ``values`` (segment r has
    ``counts[r]`` elements); NaN for an empty segment. Reorders ``values`` within segments."""
    out = np.full(counts.size, np.nan)
    buf = np.empty(max(counts.max(), 1) if counts.size else 1)
    start = 0
    for r in range(counts.size):
        n = counts[r]
        if n > 0:
            out[r] = _median(values, start, start + n, buf)
            start += n
    return out


def _interpolate_rows(medians: np.ndarray) -> np.ndarray:
    """Row elevations with rows without points interpolated (a default fan when none has any)."""
    n_rows = medians.size
    ok = np.isfinite(medians)
    if ok.all():
        return medians
    if not ok.any():
        return np.linspace(np.radians(3.0), np.radians(-25.0), n_rows)
    idx = np.arange(n_rows)
    return np.interp(idx, idx[ok], medians[ok])


def _points_for_kernel(points: np.ndarray) -> np.ndarray:
    """The x, y, z columns as a C-contiguous float32 or float64 array (no copy when they are)."""
    xyz = points[:, :3]
    if xyz.dtype not in (np.float32, np.float64):
        xyz = xyz.astype(np.float64)
    return np.ascontiguousarray(xyz)


def project_points(
    points: np.ndarray,
    width: int = 2048,
    mode: str = "rings",
    rows: int = 64,
    fov_up_deg: float = 3.0,
    fov_down_deg: float = -25.0,
    keep: np.ndarray | None = None,
    min_ring_points: int = 200,
) -> RangeImage:
    """Project a scan (in sensor scan order) into a range image.

    Parameters
    ----------
    points : (N, 3+) float array, metres, sensor frame, finite coordinates.
    width : number of columns (azimuth bins over 360 deg).
    mode : ``"rings"`` recovers the rows from the scan order (falls back to ``"spherical"`` with a
        warning when that fails); ``"spherical"`` bins the elevation uniformly over the vertical
        field of view ``[fov_down_deg, fov_up_deg]``.
    rows : number of rows (beams).
    keep : (N,) bool, the points that go into the image (e.g. all but the ground classes). Rows
        are recovered from the whole scan, so removing points does not break the ring recovery.
    min_ring_points : ring recovery fails when a ring has fewer points (see
        :func:`recover_rings`).

    Returns
    -------
    RangeImage
        Over the kept points: ``point_pixel`` has one entry per kept point; ``counts`` holds the
        number of kept points per pixel.
    """
    if mode not in ("rings", "spherical"):
        raise ValueError(f"unknown projection mode {mode!r} (rings | spherical)")
    xyz = _points_for_kernel(points)
    if keep is not None:
        keep = np.asarray(keep)
        if keep.dtype != np.bool_ or keep.shape != (xyz.shape[0],):
            raise ValueError(
                f"keep must be a ({xyz.shape[0]},) bool mask, got {keep.dtype} {keep.shape}"
            )
    flat = xyz.reshape(-1)
    x64, y64, rng, sin_elev = _point_geometry(flat, xyz.shape[0])
    az = np.arctan2(y64, x64, out=x64)
    del y64
    ring_counts = _ring_counts(az, rows, min_ring_points) if mode == "rings" else None
    if ring_counts is not None:
        use_keep = keep is not None
        ranges, counts, pix = _ring_pixels(
            rng, az, ring_counts, keep if use_keep else np.ones(1, dtype=bool), use_keep, width
        )
        # median elevation of every ring (rings are consecutive in scan order)
        elev_pts = np.arcsin(sin_elev, out=sin_elev)
        elevation = _interpolate_rows(_segment_medians(elev_pts, ring_counts))
        return RangeImage(
            ranges.reshape(rows, width), elevation, pix, "rings", counts.reshape(rows, width)
        )
    if mode == "rings":
        warnings.warn(
            f"ring recovery did not find {rows} rings in scan order; "
            "using a spherical projection for this scan",
            stacklevel=2,
        )
    elev = np.arcsin(sin_elev, out=sin_elev)
    return _project_spherical(xyz, az, elev, width, rows, fov_up_deg, fov_down_deg, keep)


@njit(cache=True)
def _ranges_kernel(flat: np.ndarray, n: int) -> np.ndarray:
    """(N,) float64 range of every point of ``(3N,)`` xyz (see :func:`_range`)."""
    out = np.empty(n, dtype=np.float64)
    for i in range(n):
        out[i] = _range(flat, i)
    return out


@njit(cache=True)
def _nearest_per_pixel(
    rng: np.ndarray, pix: np.ndarray, n_pixels: int
) -> tuple[np.ndarray, np.ndarray]:
    """Range of the nearest point per pixel (0 = none) and points per pixel."""
    ranges = np.zeros(n_pixels, dtype=np.float32)
    counts = np.zeros(n_pixels, dtype=np.int32)
    for i in range(pix.size):
        p = pix[i]
        if ranges[p] == 0.0 or rng[i] < ranges[p]:
            ranges[p] = rng[i]
        counts[p] += 1
    return ranges, counts


def _project_spherical(
    xyz: np.ndarray,
    az: np.ndarray,
    elev: np.ndarray,
    width: int,
    rows: int,
    fov_up_deg: float,
    fov_down_deg: float,
    keep: np.ndarray | None,
) -> RangeImage:
    """Spherical projection: rows bin the elevation (radians, per point) uniformly over the
    vertical field of view."""
    rng = _ranges_kernel(xyz.reshape(-1), xyz.shape[0])
    cols = np.floor((np.pi - az) / (2.0 * np.pi) * width).astype(np.int64) % width
    if keep is not None:
        rng, elev, cols = rng[keep], elev[keep], cols[keep]
    up, down = np.radians(fov_up_deg), np.radians(fov_down_deg)
    r_idx = np.floor((up - elev) / (up - down) * rows).astype(np.int64)
    inside = (r_idx >= 0) & (r_idx < rows) & (rng > 0)
    elevation = up - (np.arange(rows) + 0.5) * (up - down) / rows
    pix_in = r_idx[inside] * width + cols[inside]
    ranges, counts = _nearest_per_pixel(rng[inside].astype(np.float32), pix_in, rows * width)
    pix = np.full(rng.shape[0], -1, dtype=np.int64)
    pix[inside] = pix_in
    return RangeImage(
        ranges.reshape(rows, width),
        elevation,
        pix,
        "spherical",
        counts.reshape(rows, width),
    )


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

"""The projection step: a SemanticKITTI scan into the range image that every image method sees.

:class:`Projection` is the component (its fields are the ``[projection]`` table of a config, with
the one default of each); :func:`project_points` does the work: rows from the ring recovery
(:func:`recover_rings`) or a spherical projection, columns from the azimuth, the nearest point of a
pixel defining its range. Moosmann logs come as range images already and are not projected
(:func:`flic_cli.range_image.from_sensor_image`).
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from numba import njit
from pydantic import Field, model_validator
from pydantic.dataclasses import dataclass

from flic_cli.component import STRICT
from flic_cli.range_image import RangeImage


@dataclass(frozen=True, config=STRICT)
class Projection:
    """How a scan becomes a range image (docs/decisions.md).

    Attributes
    ----------
    mode : ``"rings"``: rows recovered from the scan order (falls back to spherical, with a
        warning naming the scan, when the scan is not in sensor order); ``"spherical"``: uniform
        elevation bins over ``[fov_down_deg, fov_up_deg]``.
    width : columns over 360 degrees.
    rows : beams (rows of the image).
    fov_up_deg, fov_down_deg : vertical field of view of the spherical projection, degrees.
    """

    mode: Literal["rings", "spherical"] = "rings"
    width: Annotated[int, Field(ge=8, le=65536, description="columns over 360 deg")] = 2048
    rows: Annotated[int, Field(ge=1, le=1024, description="beams")] = 64
    fov_up_deg: Annotated[float, Field(gt=-90, lt=90, description="degrees")] = 3.0
    fov_down_deg: Annotated[float, Field(gt=-90, lt=90, description="degrees")] = -25.0

    @model_validator(mode="after")
    def _fov_order(self) -> Projection:
        if self.fov_up_deg <= self.fov_down_deg:
            raise ValueError(
                f"fov_up_deg ({self.fov_up_deg}) must be above fov_down_deg ({self.fov_down_deg})"
            )
        return self

    def __call__(self, points: np.ndarray, keep: np.ndarray | None = None) -> RangeImage:
        """The range image of ``points`` (see :func:`flic_cli.projection.project_points`)."""
        return project_points(
            points,
            width=self.width,
            mode=self.mode,
            rows=self.rows,
            fov_up_deg=self.fov_up_deg,
            fov_down_deg=self.fov_down_deg,
            keep=keep,
        )


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
    flat: np.ndarray,
    ring_counts: np.ndarray,
    keep: np.ndarray,
    use_keep: bool,
    width: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Nearest-point range image, points per pixel, pixel of every kept point and the nearest
    point's height per pixel (``rng``: the points' ranges in metres; ``flat``: their (3N,) xyz).

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
    z = np.zeros(rows * width, dtype=np.float32)
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
                z[p] = flat[3 * i + 2]
            counts[p] += 1
            pix[j] = p
            j += 1
        start = stop
    return ranges, counts, pix[:j], z


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
    width: int = Projection.width,
    mode: str = Projection.mode,
    rows: int = Projection.rows,
    fov_up_deg: float = Projection.fov_up_deg,
    fov_down_deg: float = Projection.fov_down_deg,
    keep: np.ndarray | None = None,
    min_ring_points: int = 200,
) -> RangeImage:
    """Project a scan (in sensor scan order) into a range image.

    The defaults are those of :class:`Projection`. When the ring recovery fails (``mode =
    "rings"`` on a scan that is not in sensor order) the spherical projection is used and the
    returned image says so (``projection == "spherical"``); the caller, which knows the scan's
    file, warns.

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
        ranges, counts, pix, z = _ring_pixels(
            rng,
            az,
            flat,
            ring_counts,
            keep if use_keep else np.ones(1, dtype=bool),
            use_keep,
            width,
        )
        # median elevation of every ring (rings are consecutive in scan order)
        elev_pts = np.arcsin(sin_elev, out=sin_elev)
        elevation = _interpolate_rows(_segment_medians(elev_pts, ring_counts))
        shape = (rows, width)
        return RangeImage(
            ranges.reshape(shape), elevation, pix, "rings", counts.reshape(shape), z.reshape(shape)
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
    rng: np.ndarray, z: np.ndarray, pix: np.ndarray, n_pixels: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Range of the nearest point per pixel (0 = none), points per pixel and the nearest
    point's height ``z`` per pixel."""
    ranges = np.zeros(n_pixels, dtype=np.float32)
    counts = np.zeros(n_pixels, dtype=np.int32)
    heights = np.zeros(n_pixels, dtype=np.float32)
    for i in range(pix.size):
        p = pix[i]
        if ranges[p] == 0.0 or rng[i] < ranges[p]:
            ranges[p] = rng[i]
            heights[p] = z[i]
        counts[p] += 1
    return ranges, counts, heights


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
    z = xyz[:, 2]
    if keep is not None:
        rng, elev, cols, z = rng[keep], elev[keep], cols[keep], z[keep]
    up, down = np.radians(fov_up_deg), np.radians(fov_down_deg)
    r_idx = np.floor((up - elev) / (up - down) * rows).astype(np.int64)
    inside = (r_idx >= 0) & (r_idx < rows) & (rng > 0)
    elevation = up - (np.arange(rows) + 0.5) * (up - down) / rows
    pix_in = r_idx[inside] * width + cols[inside]
    ranges, counts, heights = _nearest_per_pixel(
        rng[inside].astype(np.float32), z[inside].astype(np.float32), pix_in, rows * width
    )
    pix = np.full(rng.shape[0], -1, dtype=np.int64)
    pix[inside] = pix_in
    return RangeImage(
        ranges.reshape(rows, width),
        elevation,
        pix,
        "spherical",
        counts.reshape(rows, width),
        heights.reshape(rows, width),
        every_point_has_pixel=False,
    )

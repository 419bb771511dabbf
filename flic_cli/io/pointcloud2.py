"""``sensor_msgs/PointCloud2`` without ROS: the point fields as numpy, and the range image of a
cloud whose points carry their beam (``ring`` / ``channel``).

A PointCloud2 declares its layout: ``fields`` (name, byte offset, datatype, count),
``point_step``, ``row_step``, ``height`` x ``width`` and ``is_bigendian``. :func:`cloud_array`
turns the message's ``data`` into a numpy structured array of exactly that layout (a view, no
per-point Python loop); :func:`ring_image` bins the points into an image whose rows are the
beams and whose columns are the azimuth, the nearest point of a pixel defining its range (one
numba pass).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit

from flic_cli.errors import FlicInputError
from flic_cli.range_image import RangeImage

#: PointField datatype codes (sensor_msgs/PointField) -> numpy type code.
DATATYPES: dict[int, str] = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}

#: Names drivers give the beam index of a point, tried in this order.
RING_FIELDS = ("ring", "channel", "laser_id", "line")
#: Names drivers give the time of a point within the revolution.
TIME_FIELDS = ("time", "t", "timestamp", "time_stamp", "offset_time")
#: Names drivers give the intensity of a point.
INTENSITY_FIELDS = ("intensity", "reflectivity", "signal")


def cloud_dtype(fields: list[Any], point_step: int, bigendian: bool) -> np.dtype:
    """The numpy structured dtype of a PointCloud2's points, as its fields declare it.

    Parameters
    ----------
    fields : the message's ``sensor_msgs/PointField`` list (``name``, ``offset``,
        ``datatype``, ``count``).
    point_step : bytes per point.
    bigendian : the message's ``is_bigendian``.

    Raises
    ------
    ValueError
        On an unknown datatype, a field outside ``point_step`` or two fields of one name.
    """
    order = ">" if bigendian else "<"
    names, formats, offsets = [], [], []
    for f in fields:
        code = DATATYPES.get(int(f.datatype))
        if code is None:
            raise ValueError(f"field {f.name!r} has unknown datatype {f.datatype}")
        count = max(int(f.count), 1)
        fmt = np.dtype(order + code) if count == 1 else np.dtype((order + code, (count,)))
        if int(f.offset) + fmt.itemsize > point_step:
            raise ValueError(
                f"field {f.name!r} (offset {f.offset}, {fmt.itemsize} bytes) lies outside the "
                f"point_step of {point_step} bytes"
            )
        if f.name in names:
            raise ValueError(f"field {f.name!r} is declared twice")
        names.append(f.name)
        formats.append(fmt)
        offsets.append(int(f.offset))
    return np.dtype(
        {"names": names, "formats": formats, "offsets": offsets, "itemsize": point_step}
    )


def cloud_array(msg: Any) -> np.ndarray:
    """The points of a PointCloud2 message as a structured array (``height * width`` points in
    the message's order; a view on ``msg.data`` when rows are not padded).

    Raises
    ------
    ValueError
        When the layout is inconsistent (see :func:`cloud_dtype`) or ``data`` is shorter than
        ``height * row_step`` bytes.
    """
    step = int(msg.point_step)
    dtype = cloud_dtype(list(msg.fields), step, bool(msg.is_bigendian))
    h, w, row_step = int(msg.height), int(msg.width), int(msg.row_step)
    data = np.asarray(msg.data, dtype=np.uint8).reshape(-1)
    if h * w == 0:
        return np.zeros(0, dtype=dtype)
    if row_step < w * step:
        raise ValueError(f"row_step {row_step} is below width x point_step = {w * step}")
    if data.size < (h - 1) * row_step + w * step:
        raise ValueError(
            f"data holds {data.size} bytes, the layout needs {(h - 1) * row_step + w * step} "
            f"({h} x {w} points of {step} bytes, row_step {row_step})"
        )
    if row_step == w * step:
        return data[: h * w * step].view(dtype)
    rows = np.lib.stride_tricks.as_strided(data, shape=(h, w * step), strides=(row_step, 1))
    return np.ascontiguousarray(rows).reshape(-1).view(dtype)


def first_field(names: tuple[str, ...] | list[str], wanted: tuple[str, ...]) -> str | None:
    """The first of ``wanted`` that ``names`` has, or None."""
    return next((n for n in wanted if n in names), None)


def xyz_of(cloud: np.ndarray, where: Path | str, topic: str) -> np.ndarray:
    """(N, 3) float32 C-contiguous x, y, z of a structured cloud.

    Raises
    ------
    FlicInputError
        Naming the bag and topic when a coordinate field is missing or not a scalar.
    """
    names = cloud.dtype.names or ()
    missing = [c for c in "xyz" if c not in names]
    if missing:
        raise FlicInputError(
            where,
            f"topic {topic}: PointCloud2 has no {'/'.join(missing)} field "
            f"(fields: {', '.join(names) or 'none'})",
        )
    if any(cloud.dtype.fields[c][0].shape for c in "xyz"):
        raise FlicInputError(where, f"topic {topic}: PointCloud2 x/y/z fields have count > 1")
    xyz = np.empty((cloud.shape[0], 3), dtype=np.float32)
    for j, c in enumerate("xyz"):
        xyz[:, j] = cloud[c]
    return xyz


@dataclass(frozen=True)
class Beams:
    """A spinning sensor's beams as a cloud's ring field numbers them.

    Attributes
    ----------
    row_of_ring : (R,) int64, the image row of every ring number (row 0 = top beam); -1 for ring
        numbers the sensor does not have.
    elevation : (H,) float64 elevation of every row in radians, positive up; rows no point of
        the reference cloud fell on are interpolated.
    width : columns per revolution.
    source : how the beams were found, for ``flic info``.
    """

    row_of_ring: np.ndarray
    elevation: np.ndarray
    width: int
    source: str

    @property
    def rows(self) -> int:
        return int(self.elevation.size)


def estimate_beams(
    xyz: np.ndarray, ring: np.ndarray, width: int | None = None, source: str = ""
) -> Beams:
    """The beams of a sensor from one revolution whose points carry their ring number.

    Rows are the ring numbers ordered by elevation (row 0 = top): when the rings that have
    points are monotonic in elevation (every driver's ``ring`` field), all ring numbers
    ``0..max`` are rows in that order, rings without points in between taking interpolated
    elevations; otherwise only rings with points are rows, sorted by elevation. The
    elevation of a ring is the median of its points' ``atan2(z, hypot(x, y))``. The columns per
    revolution, unless given, come from the median azimuth step between neighbouring points of
    the ring with the most points.

    Parameters
    ----------
    xyz : (N, 3) float points in metres (non-finite or zero-range points are ignored).
    ring : (N,) integer ring number of every point.
    width : columns per revolution, when known (an organised cloud's width, a decoder's).
    source : how the ring numbers were obtained, recorded in :attr:`Beams.source`.
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    ring = np.asarray(ring).astype(np.int64)
    rng = np.sqrt((xyz**2).sum(axis=1))
    ok = np.isfinite(rng) & (rng > 0) & (ring >= 0)
    xyz, ring = xyz[ok], ring[ok]
    n_rings = int(ring.max()) + 1 if ring.size else 1
    elev = np.arctan2(xyz[:, 2], np.hypot(xyz[:, 0], xyz[:, 1]))
    med = np.full(n_rings, np.nan)
    order = np.argsort(ring, kind="stable")
    ring_sorted, elev_sorted = ring[order], elev[order]
    bounds = np.searchsorted(ring_sorted, np.arange(n_rings + 1))
    for r in range(n_rings):
        if bounds[r + 1] > bounds[r]:
            med[r] = np.median(elev_sorted[bounds[r] : bounds[r + 1]])
    has = np.flatnonzero(np.isfinite(med))
    if has.size == 0:
        med[:] = np.linspace(np.radians(15.0), np.radians(-15.0), n_rings)
        has = np.arange(n_rings)
    d = np.diff(med[has])
    if d.size == 0 or (d > 0).all() or (d < 0).all():
        full = (
            np.interp(np.arange(n_rings), has, med[has])
            if has.size > 1
            else med[has][[0] * n_rings]
        )
        if has.size > 1:  # extrapolate beyond the outermost rings with points
            step = (med[has[-1]] - med[has[0]]) / (has[-1] - has[0])
            lo, hi = np.arange(n_rings) < has[0], np.arange(n_rings) > has[-1]
            full[lo] = med[has[0]] - step * (has[0] - np.arange(n_rings)[lo])
            full[hi] = med[has[-1]] + step * (np.arange(n_rings)[hi] - has[-1])
        rings_by_row = np.argsort(-full, kind="stable")
        elevation = full[rings_by_row]
    else:
        rings_by_row = has[np.argsort(-med[has], kind="stable")]
        elevation = med[rings_by_row]
    row_of_ring = np.full(n_rings, -1, dtype=np.int64)
    row_of_ring[rings_by_row] = np.arange(rings_by_row.size)
    if width is None:
        width = _columns_per_revolution(xyz, ring)
    return Beams(row_of_ring, elevation.astype(np.float64), int(width), source)


def _columns_per_revolution(xyz: np.ndarray, ring: np.ndarray) -> int:
    """Columns per revolution: 2 pi over the median azimuth step within the fullest ring."""
    if ring.size == 0:
        return 2048
    fullest = np.bincount(ring).argmax()
    az = np.sort(np.arctan2(xyz[ring == fullest, 1], xyz[ring == fullest, 0]))
    steps = np.diff(az)
    steps = steps[steps > 1e-5]  # several returns of one firing share their azimuth
    if steps.size == 0:
        return 2048
    return int(np.clip(round(2.0 * np.pi / float(np.median(steps))), 8, 65536))


def ring_image(xyz: np.ndarray, ring: np.ndarray, beams: Beams) -> tuple[RangeImage, np.ndarray]:
    """The range image of one revolution: rows from the points' rings, columns from their
    azimuth.

    The column of a point is ``floor((pi - atan2(y, x)) / (2 pi) * width) mod width`` (column 0
    looks backwards, as everywhere in flic; the azimuth in float32); a pixel's range is that of
    its nearest point.

    Parameters
    ----------
    xyz : (N, 3) float32 C-contiguous points in metres, as stored (NaN, zero-range points and
        points of unknown rings are left out).
    ring : (N,) integer ring number of every point.
    beams : the sensor's beams (:func:`estimate_beams`).

    Returns
    -------
    image : RangeImage with ``projection = "rings"`` over the kept points.
    kept : (N,) bool, the points in the image (finite, range > 0, a known ring).
    """
    xyz = np.ascontiguousarray(xyz, dtype=np.float32)
    ring = np.ascontiguousarray(ring)
    if ring.dtype.kind not in "iu" or not ring.dtype.isnative:  # float or big-endian rings
        ring = ring.astype(np.int64)
    # numpy's vectorised arctan2 (float32, SIMD): numba's scalar atan2 call costs 25x more
    with np.errstate(invalid="ignore"):
        azimuth = np.arctan2(xyz[:, 1], xyz[:, 0])
    ranges, counts, z, pix, kept = _ring_kernel(
        xyz, azimuth, ring, beams.row_of_ring, beams.rows, beams.width
    )
    shape = (beams.rows, beams.width)
    image = RangeImage(
        ranges.reshape(shape),
        beams.elevation,
        pix,
        "rings",
        counts.reshape(shape),
        z.reshape(shape),
    )
    return image, kept


@njit(cache=True)
def _ring_kernel(
    xyz: np.ndarray,
    azimuth: np.ndarray,
    ring: np.ndarray,
    row_of_ring: np.ndarray,
    rows: int,
    width: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    n = xyz.shape[0]
    n_rings = row_of_ring.size
    ranges = np.zeros(rows * width, dtype=np.float32)
    counts = np.zeros(rows * width, dtype=np.int32)
    z = np.zeros(rows * width, dtype=np.float32)
    pix = np.empty(n, dtype=np.int64)
    kept = np.zeros(n, dtype=np.bool_)
    scale = width / (2.0 * np.pi)
    j = 0
    for i in range(n):
        x = np.float64(xyz[i, 0])
        y = np.float64(xyz[i, 1])
        zz = np.float64(xyz[i, 2])
        r = np.sqrt(x * x + y * y + zz * zz)
        k = np.int64(ring[i])
        if not (r > 0.0) or not np.isfinite(r) or k < 0 or k >= n_rings:
            continue
        row = row_of_ring[k]
        if row < 0:
            continue
        c = np.int64(np.floor((np.pi - np.float64(azimuth[i])) * scale))
        if c >= width or c < 0:
            c %= width
        p = row * width + c
        rf = np.float32(r)
        if ranges[p] == 0.0 or rf < ranges[p]:
            ranges[p] = rf
            z[p] = xyz[i, 2]
        counts[p] += 1
        pix[j] = p
        kept[i] = True
        j += 1
    return ranges, counts, z, pix[:j], kept

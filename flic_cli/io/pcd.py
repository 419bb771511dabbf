"""PCD point clouds (ASCII, binary, binary_compressed), read with pypcd4; one frame per file.

The range image: an organised cloud (HEIGHT > 1, as ROS drivers write Ouster and Velodyne
clouds) keeps its rows and columns. Otherwise rows come from a ring field (``ring``,
``channel``, ``laser_id``, ``line``; ids in elevation order are rows, else the rings are ranked
by their points' median elevation, so the top beam is row 0 whatever the numbering), columns
from an ``azimuth`` field when there is one, else from the points' azimuth, and the number of
columns from the median azimuth step between a ring's neighbouring points.

Azimuth units are detected from the values: at most 2 pi + 0.01 -> radians, at most 360.5 ->
degrees, at most 36,000 x 1.05 -> 0.01 degree (RoboSense / nebula's ``azimuth``); the field's
direction and zero (clockwise or counter-clockwise, from which axis) are fitted against the
points' own azimuths. Without a ring field the beams are estimated from the points' elevations
(gaps between sorted elevations); ``flic info`` says which was used.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flic_cli.errors import FlicInputError
from flic_cli.io.base import Frame, FrameRef
from flic_cli.io.rings import azimuth_columns, ring_image
from flic_cli.io.sensor import FileInfo, SensorFileDataset, SensorModel

FORMAT = "pcd"
RING_FIELDS = ("ring", "channel", "laser_id", "line")


def azimuth_unit(values: np.ndarray) -> tuple[str, float]:
    """``(unit name, radians per unit)`` of an azimuth field, from its largest magnitude.

    Raises
    ------
    ValueError
        When the values fit none of radians, degrees and 0.01 degree.
    """
    top = float(np.nanmax(np.abs(values))) if values.size else 0.0
    if top <= 2 * np.pi + 0.01:
        return "radians", 1.0
    if top <= 360.5:
        return "degrees", np.pi / 180
    if top <= 36000 * 1.05:
        return "0.01 degree", np.pi / 18000
    raise ValueError(f"azimuth values up to {top:g} fit neither radians, degrees nor 0.01 degree")


def fit_azimuth(field_rad: np.ndarray, atan_az: np.ndarray) -> tuple[float, float]:
    """``(sign, zero)`` so that ``sign * field + zero`` is the counter-clockwise azimuth from x
    (radians), fitted on the points: the sign whose residuals have the larger circular
    concentration, the zero their circular mean."""
    best = (1.0, 0.0, -1.0)
    for sign in (1.0, -1.0):
        d = atan_az - sign * field_rad
        c, s = float(np.mean(np.cos(d))), float(np.mean(np.sin(d)))
        strength = np.hypot(c, s)
        if strength > best[2]:
            best = (sign, float(np.arctan2(s, c)), strength)
    return best[0], best[1]


def estimate_width(azimuth: np.ndarray, ring: np.ndarray) -> int:
    """Columns per revolution from the median azimuth step (radians) between neighbouring points
    of a ring (sorted by azimuth, repeated azimuths of dual returns skipped).

    The step is the cloud's own point spacing: where a ring returns only every other firing
    (the Helios-16P recording: steps of 0.1 and 0.2 deg), that gives W for the finer spacing, and
    row neighbours are then often a column apart; the ``columns`` reader option states W."""
    steps = []
    for r in np.unique(ring):
        a = np.unique(np.sort(azimuth[ring == r]))
        if a.size > 8:
            d = np.diff(a)
            steps.append(d[d > 1e-6])
    if not steps:
        return 1024
    step = float(np.median(np.concatenate(steps)))
    return int(np.clip(round(2 * np.pi / step), 8, 65536))


def estimate_rings(
    points: np.ndarray, gap_deg: float = 0.4, beams: int | None = None
) -> np.ndarray | None:
    """Ring of every point (0 = lowest) from gaps between its sorted elevations, or None when
    that finds no plausible beam structure (under 2 or over 256 beams, or beams of under 20
    points on average).

    Parameters
    ----------
    points : (N, 3) xyz, metres.
    gap_deg : a gap wider than this (degrees) between neighbouring elevations starts a beam.
    beams : the number of beams when known (the ``rows`` reader option): the ``beams - 1``
        widest gaps separate them then, ``gap_deg`` is not used.
    """
    xyz = points.astype(np.float64)
    el = np.degrees(np.arctan2(xyz[:, 2], np.hypot(xyz[:, 0], xyz[:, 1])))
    order = np.argsort(el)
    diff = np.diff(el[order])
    if beams is not None:
        if beams < 1 or beams > diff.size + 1:
            return None
        gaps = np.zeros(diff.size, dtype=bool)
        gaps[np.argsort(diff, kind="stable")[diff.size - beams + 1 :]] = True
    else:
        gaps = diff > gap_deg
    ring_sorted = np.concatenate([[0], np.cumsum(gaps)])
    n = int(ring_sorted[-1]) + 1 if ring_sorted.size else 0
    if beams is None and (n < 2 or n > 256 or points.shape[0] / n < 20):
        return None
    ring = np.empty(points.shape[0], dtype=np.int64)
    ring[order] = ring_sorted
    return ring


def _rank_rings(points: np.ndarray, ring: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rings renumbered 0 = lowest by their median elevation, and the (H,) row elevations (row
    0 = top, radians)."""
    ids, inv = np.unique(ring, return_inverse=True)
    xyz = points.astype(np.float64)
    el = np.arctan2(xyz[:, 2], np.hypot(xyz[:, 0], xyz[:, 1]))
    med = np.array([np.median(el[inv == k]) for k in range(ids.size)])
    rank = np.empty(ids.size, dtype=np.int64)
    rank[np.argsort(med, kind="stable")] = np.arange(ids.size)
    return rank[inv], np.sort(med)[::-1].copy()


@dataclass
class CloudGeometry:
    """How the points of a cloud map to pixels (found once per file, reused per load)."""

    ring: np.ndarray  # (N_kept,) 0 = lowest
    column: np.ndarray  # (N_kept,)
    width: int
    elevation: np.ndarray  # (H,) row 0 = top
    model: SensorModel


def cloud_geometry(
    points: np.ndarray,
    ring: np.ndarray | None,
    azimuth: np.ndarray | None,
    name: str,
    source: str,
    beams: int | None = None,
    columns: int | None = None,
    rows: int | None = None,
) -> CloudGeometry:
    """Rows, columns and the sensor model of a cloud (see the module docs).

    Parameters
    ----------
    points : (N, 3) xyz of the points kept (finite, not at the origin).
    ring : (N,) ring field or None (estimated then).
    azimuth : (N,) azimuth field (any unit, detected) or None (the points' azimuth then).
    name, source : the sensor's name and the file it came from (for the notes).
    beams : the sensor's beam count when known (rings without points then still get a row).
    columns : columns per revolution W (the ``columns`` reader option); None = estimated from
        the median azimuth step (:func:`estimate_width`).
    rows : beams of a cloud without ring field (the ``rows`` reader option); None = estimated
        from gaps in the elevations (:func:`estimate_rings`).
    """
    xyz = points.astype(np.float64)
    atan_az = np.arctan2(xyz[:, 1], xyz[:, 0])
    notes = []
    if ring is None:
        est = estimate_rings(points, beams=rows)
        if est is None:
            raise FlicInputError(
                source,
                "has no ring field, and no beam structure shows in its elevations"
                if rows is None
                else f"has fewer distinct elevations than the {rows} rows asked for",
            )
        ring_rank, elevation = _rank_rings(points, est)
        angles_from = "estimated"
        how = "the widest gaps" if rows is not None else "gaps"
        notes.append(f"rows: {elevation.size} beams, split at {how} in the elevations")
    else:
        ring = np.asarray(ring, dtype=np.int64)
        ids = np.unique(ring)
        el = np.arctan2(xyz[:, 2], np.hypot(xyz[:, 0], xyz[:, 1]))
        med = np.array([np.median(el[ring == k]) for k in ids])
        angles_from = "fields"
        if ids[0] >= 0 and ids[-1] < 1024 and np.all(np.diff(med) > 0):
            # numbered from the lowest beam up: ring ids are rows, ids without points too
            beams = max(int(ids[-1]) + 1, beams or 0)
            full = np.interp(np.arange(beams), ids, med)
            elevation = full[::-1].copy()
            ring_rank = ring
            if ids.size < beams:
                notes.append(f"{beams - ids.size} of {beams} rings hold no point")
        else:
            ring_rank, elevation = _rank_rings(points, ring)
            notes.append("rings ranked by elevation (the ids are not in elevation order)")
        notes.append("rows from the ring field, elevations = median per ring")
    if azimuth is not None:
        unit, scale = azimuth_unit(azimuth)
        field = azimuth.astype(np.float64) * scale
        sign, zero = fit_azimuth(field, atan_az)
        az = sign * field + zero
        notes.append(
            f"columns from the azimuth field ({unit}, "
            f"{'counter-' if sign > 0 else ''}clockwise, zero at {np.degrees(zero):+.1f} deg)"
        )
    else:
        az = atan_az
        notes.append("columns from the points' azimuth atan2(y, x)")
    width = estimate_width(az, ring_rank) if columns is None else int(columns)
    column = azimuth_columns(az, width)
    h = elevation.size
    model = SensorModel(
        name=name,
        elevation=elevation,
        azimuth_offset=np.zeros(h),
        columns=width,
        angles_from=angles_from,
        columns_from="the median azimuth step (estimated)" if columns is None else "--columns",
        notes=tuple(notes),
    )
    return CloudGeometry(ring_rank, column, width, elevation, model)


def organised_geometry(
    points: np.ndarray, kept: np.ndarray, width: int, height: int, name: str
) -> CloudGeometry:
    """Rows and columns of an organised cloud (HEIGHT rows of WIDTH points, a beam per row, as
    ROS drivers write Ouster and Velodyne clouds): row and column from the point's position,
    rows turned so that row 0 is the top beam, columns turned and rolled to the image's azimuth
    convention (fitted against the points' azimuths).

    Parameters
    ----------
    points : (N_kept, 3) xyz of the points kept.
    kept : (width * height,) bool, which stored points those are.
    """
    index = np.flatnonzero(kept)
    row, col = index // width, index % width
    xyz = points.astype(np.float64)
    el = np.arctan2(xyz[:, 2], np.hypot(xyz[:, 0], xyz[:, 1]))
    med = np.full(height, np.nan)
    for r in np.unique(row):
        med[r] = np.median(el[row == r])
    have = np.flatnonzero(~np.isnan(med))
    top_first = have.size < 2 or med[have[0]] > med[have[-1]]
    ring = (height - 1 - row) if top_first else row  # 0 = lowest
    full = np.interp(np.arange(height), have, med[have]) if have.size else np.zeros(height)
    elevation = full if top_first else full[::-1].copy()
    step = 2 * np.pi / width
    sign, zero = fit_azimuth(col * step, np.arctan2(xyz[:, 1], xyz[:, 0]))
    # azimuth = zero + sign * col * step; the image wants pi - (c + 0.5) * step
    c0 = (np.pi - zero) / step - 0.5
    column = np.rint(c0 - sign * col).astype(np.int64) % width
    model = SensorModel(
        name=name,
        elevation=elevation,
        azimuth_offset=np.zeros(height),
        columns=width,
        angles_from="fields",
        columns_from="the organised cloud's WIDTH",
        notes=(
            f"organised cloud: {height} rows x {width} columns (HEIGHT x WIDTH)",
            "rows from the point's row, elevations = median per row",
        ),
    )
    return CloudGeometry(np.asarray(ring, dtype=np.int64), column, width, elevation, model)


def read_pcd(path: str | Path, fields: tuple[str, ...] | None = None) -> np.ndarray:
    """The points of a PCD file as a structured array; see :func:`read_pcd_shape`."""
    return read_pcd_shape(path, fields)[0]


def read_pcd_shape(
    path: str | Path, fields: tuple[str, ...] | None = None
) -> tuple[np.ndarray, int, int]:
    """``(points, width, height)`` of a PCD file: the structured array and the header's WIDTH
    and HEIGHT (an organised cloud has HEIGHT > 1: one row per beam).

    pypcd4 parses the header and reads binary and binary_compressed data. An ASCII data section
    is parsed by pandas' C reader instead (pypcd4 uses ``numpy.loadtxt``, several times
    slower), and only the ``fields`` asked for are converted.

    Parameters
    ----------
    path : the file.
    fields : the fields needed (of an ASCII section only those are parsed and returned;
        binary data comes whole); None = all.

    Raises
    ------
    FlicInputError
        When it cannot be read, holds fewer points than its header says (ASCII), or has no
        x, y, z fields.
    """
    try:
        from pypcd4 import MetaData, PointCloud
    except ImportError:  # pragma: no cover - a core dependency
        raise FlicInputError(path, "reading PCD needs pypcd4 (pip install pypcd4)") from None
    try:
        with open(path, "rb") as fp:
            meta = MetaData.parse_header(_header_lines(fp))
            names = meta.build_dtype().names or ()
            missing = [c for c in "xyz" if c not in names]
            if missing:
                raise FlicInputError(
                    path,
                    f"has no {'/'.join(missing)} field (fields: {', '.join(names) or 'none'}): "
                    "a PCD needs x, y and z",
                )
            if meta.data.value == "ascii":
                data = _ascii_data(fp, meta, fields, path)
            else:
                fp.seek(0)
                data = PointCloud.from_fileobj(fp).pc_data
    except FlicInputError:
        raise
    except Exception as exc:  # noqa: BLE001 - pypcd4 and pandas raise many kinds on bad files
        raise FlicInputError(
            path, f"is not a readable PCD file ({type(exc).__name__}: {exc})"
        ) from None
    return data, int(meta.width), int(meta.height)


def _header_lines(fp) -> list[str]:  # noqa: ANN001
    """The header lines of a PCD file, as pypcd4's ``PointCloud.from_fileobj`` collects them
    (comments and blank lines skipped, up to DATA), leaving ``fp`` at the data section."""
    lines: list[str] = []
    for raw in fp:
        line = raw.decode("utf-8").strip()
        if line.startswith("#") or not line:
            continue
        lines.append(line)
        if line.startswith("DATA") or len(lines) >= 10:
            break
    return lines


def _ascii_data(fp, meta, fields: tuple[str, ...] | None, path: object) -> np.ndarray:  # noqa: ANN001
    """An ASCII data section (one point per line, values separated by spaces) read by pandas'
    C parser: the requested fields as a structured array of the header's types."""
    import pandas as pd

    dtype = meta.build_dtype()
    names = list(dtype.names)
    wanted = names if fields is None else [n for n in names if n in fields]
    if meta.points == 0:
        return np.empty(0, [(n, dtype[n]) for n in wanted])
    start = fp.tell()
    first = fp.readline().rstrip(b"\r\n").split(b" ")
    fp.seek(start)
    # one space between values (as PCL writes them) is pandas' fast path; other spacing is
    # parsed as any whitespace (three times slower here)
    single = len(first) == len(names) and all(first)
    # pandas 3's C reader rounds every number correctly (as numpy.loadtxt, pypcd4's reader);
    # pandas 2's default ("high") is off by a unit in the last place for about a third of
    # 17-digit doubles, its "round_trip" (Python's strtod) is exact
    exact = {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
    frame = pd.read_csv(
        fp, sep=" " if single else r"\s+", header=None, names=names, usecols=wanted,
        nrows=meta.points, dtype={n: dtype[n] for n in wanted}, engine="c", **exact,
    )  # fmt: skip
    if len(frame) != meta.points:
        raise FlicInputError(
            path, f"holds {len(frame):,} of the {meta.points:,} points its header declares"
        )
    out = np.empty(len(frame), [(n, dtype[n]) for n in wanted])
    for n in wanted:
        out[n] = frame[n].to_numpy()
    return out


def kept_points(xyz: np.ndarray, min_range: float = 0.0) -> np.ndarray:
    """(N,) bool: finite points farther than ``min_range`` metres (and not at the origin)."""
    finite = np.isfinite(xyz).all(axis=1)
    safe = np.where(finite[:, None], xyz, 0).astype(np.float64)
    r2 = np.einsum("ij,ij->i", safe, safe)
    return finite & (r2 > max(min_range, 1e-6) ** 2)


@dataclass
class _PcdState:
    keep: np.ndarray | None  # over the stored points; None = all
    geometry: CloudGeometry


class PcdDataset(SensorFileDataset):
    """A ``.pcd`` file or a folder of them (implements :class:`flic_cli.io.base.Dataset`), one
    frame per file; points with non-finite coordinates or at the origin are left out (label
    0)."""

    format = FORMAT
    suffixes = (".pcd",)
    reader_options = ("columns", "rows")

    def _open(self, path: Path) -> FileInfo:
        data, width, height = read_pcd_shape(path)
        xyz = np.stack([data["x"], data["y"], data["z"]], axis=1).astype(np.float32)
        keep = kept_points(xyz)
        if 1 < height <= 1024 and width > 1 and width * height == xyz.shape[0] and keep.any():
            asked = (self.options.get("rows"), self.options.get("columns"))
            if asked[0] not in (None, height) or asked[1] not in (None, width):
                raise FlicInputError(
                    path, f"is an organised cloud of {height} x {width} (HEIGHT x WIDTH): "
                    "--rows / --columns cannot change that",
                )  # fmt: skip
            geo = organised_geometry(xyz[keep], keep, width, height, f"PCD ({path.name})")
            state = _PcdState(None if keep.all() else keep, geo)
            return FileInfo(path, 1, geo.model, np.array([int(keep.sum())]), [], state)
        names = data.dtype.names or ()
        ring_name = next((n for n in RING_FIELDS if n in names), None)
        ring = data[ring_name][keep].astype(np.int64) if ring_name else None
        az = data["azimuth"][keep] if "azimuth" in names else None
        if ring is not None and self.options.get("rows") is not None:
            raise FlicInputError(
                path, f"has a ring field ({ring_name!r}): its rows come from it, not --rows"
            )
        try:
            geo = cloud_geometry(
                xyz[keep], ring, az, f"PCD ({path.name})", str(path), **self.options
            )
        except ValueError as exc:
            raise FlicInputError(path, str(exc)) from None
        if ring_name:
            note = f"ring field: {ring_name!r}"
            geo.model = SensorModel(**{**geo.model.__dict__, "notes": (note,) + geo.model.notes})
        state = _PcdState(None if keep.all() else keep, geo)
        return FileInfo(path, 1, geo.model, np.array([int(keep.sum())]), [], state)

    def _load(self, info: FileInfo, k: int) -> Frame:
        state: _PcdState = info.state  # type: ignore[assignment]
        data = read_pcd(info.path, ("x", "y", "z"))
        xyz = np.stack([data["x"], data["y"], data["z"]], axis=1).astype(np.float32)
        if state.keep is not None:
            if state.keep.size != xyz.shape[0]:
                raise FlicInputError(info.path, "changed since it was opened")
            xyz = np.ascontiguousarray(xyz[state.keep])
        g = state.geometry
        image = ring_image(xyz, g.ring, g.column, g.width, g.elevation)
        ref = FrameRef(self.sequence_name(info.path), k, info.path, None, FORMAT, index=k)
        return Frame(ref, xyz, None, image, finite=state.keep)

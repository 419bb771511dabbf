"""Ouster's OSF recordings, read through ouster-sdk (optional: ``pip install --no-deps
ouster-sdk``).

OSF is Ouster's own container (a flatbuffers log of compressed lidar frames with the sensor
metadata inside). flic does not decode it itself: ouster-sdk (>= 1.0) reads the frames, and flic
takes the first sensor's staggered RANGE field of each complete frame and the metadata (its JSON,
:meth:`flic_cli.io.ouster.OusterMeta.from_json`), and builds the image and the points exactly as
for an Ouster pcap (:func:`flic_cli.io.ouster.frame_image`). ouster-sdk pins
``rosbags==0.9.23`` against flic's ``rosbags>=0.11``, so it is installed without its
dependencies (reading OSF needs only numpy of them; see docs/sensors.md).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flic_cli.errors import FlicInputError
from flic_cli.io.base import Frame, FrameRef
from flic_cli.io.ouster import OusterDataError, OusterFrame, OusterMeta, frame_image
from flic_cli.io.sensor import FileInfo, SensorFileDataset, SensorModel

FORMAT = "osf"
INSTALL = "pip install --no-deps ouster-sdk"


def _sdk():  # noqa: ANN202
    try:
        from ouster.sdk import core, open_source
    except ImportError:
        raise FlicInputError(None, f"reading OSF needs ouster-sdk ({INSTALL})") from None
    return core, open_source


def _source(path: Path):  # noqa: ANN202
    _, open_source = _sdk()
    try:
        return open_source(str(path), collate=False, sensor_idx=0)
    except Exception as exc:  # noqa: BLE001 - ouster-sdk raises RuntimeError and others
        raise FlicInputError(path, f"is not an OSF file ouster-sdk can read ({exc})") from None


@dataclass
class _OsfState:
    meta: OusterMeta
    positions: list[int]  # per complete frame: its position in the source


def _lidar_frame(frame_set: object) -> object | None:
    frames = [f for f in frame_set.valid_frames() if f is not None]  # type: ignore[attr-defined]
    return frames[0] if frames else None


class OsfDataset(SensorFileDataset):
    """An OSF file or a folder of them (implements :class:`flic_cli.io.base.Dataset`); a frame
    is one complete revolution of the first sensor."""

    format = FORMAT
    suffixes = (".osf",)

    def _open(self, path: Path) -> FileInfo:
        core, _ = _sdk()
        source = _source(path)
        info = source.sensor_info[0]
        try:
            meta = OusterMeta.from_json(json.loads(info.to_json_string()))
        except OusterDataError as exc:
            raise FlicInputError(path, f"holds metadata flic cannot use ({exc})") from None
        positions, points, partial = [], [], []
        for k, frame_set in enumerate(source):
            lf = _lidar_frame(frame_set)
            if lf is None:
                continue
            n = int(np.count_nonzero(lf.field(core.ChanField.RANGE)))
            if lf.complete(info.format.column_window):
                positions.append(k)
                points.append(n)
            else:
                partial.append(f"frame id {lf.frame_id}: incomplete, {n:,} points")
        model = meta.sensor_model()
        model = SensorModel(
            model.name, model.elevation, model.azimuth_offset, model.columns,
            model.angles_from, model.beam_origin_mm, model.columns_from,
            model.notes + ("metadata inside the OSF file, frames read by ouster-sdk",),
        )  # fmt: skip
        state = _OsfState(meta, positions)
        return FileInfo(path, len(positions), model, np.array(points), partial, state)

    def _load(self, info: FileInfo, k: int) -> Frame:
        core, _ = _sdk()
        state: _OsfState = info.state  # type: ignore[assignment]
        source = _source(info.path)
        lf = _lidar_frame(source[state.positions[k]])
        if lf is None:
            raise FlicInputError(info.path, f"frame {k} has no lidar data")
        rng = np.ascontiguousarray(lf.field(core.ChanField.RANGE), dtype=np.uint32)
        columns = np.ones(rng.shape[1], dtype=bool)
        image, points = frame_image(OusterFrame(int(lf.frame_id), rng, columns), state.meta)
        ref = FrameRef(self.sequence_name(info.path), k, info.path, None, FORMAT, index=k)
        return Frame(ref, points, None, image)

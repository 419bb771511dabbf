"""The sensor model of a recording: its beams, their angles, and where those came from.

Every sensor reader (:mod:`flic_cli.io.ouster`, :mod:`flic_cli.io.velodyne`,
:mod:`flic_cli.io.pcd`, :mod:`flic_cli.io.nuscenes`) describes its recording with a
:class:`SensorModel`; ``flic info`` prints it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from flic_cli.errors import FlicInputError
from flic_cli.io.semantickitti import export_path, write_cluster_prediction

#: Where a sensor model's beam angles came from (:attr:`SensorModel.angles_from`).
ANGLE_SOURCES = {
    "metadata": "the sensor's metadata (calibration) file",
    "decoder": "the decoder's built-in calibration for the model",
    "fields": "per-point ring / azimuth fields of the file",
    "estimated": "estimated from the points (median elevation per ring)",
}


@dataclass(frozen=True, eq=False)
class SensorModel:
    """The geometry of a spinning lidar as a range image sees it.

    Attributes
    ----------
    name : the sensor, e.g. ``"Ouster OS-2-128"`` or ``"Velodyne VLP-16"``.
    elevation : (H,) float64 elevation of every beam in radians, positive up, row 0 = top beam.
    azimuth_offset : (H,) float64 azimuth of every beam relative to its image column's nominal
        azimuth, in radians (positive = counter-clockwise seen from above); zeros where the
        source gives none.
    columns : columns per revolution (W).
    angles_from : a key of :data:`ANGLE_SOURCES`.
    beam_origin_mm : distance from the lidar origin to the beams' origin in mm (Ouster's
        ``lidar_origin_to_beam_origin_mm``), or None where the source gives none.
    columns_from : where ``columns`` came from, in a few words.
    notes : further facts for ``flic info`` (e.g. which metadata fields were defaulted).
    """

    name: str
    elevation: np.ndarray
    azimuth_offset: np.ndarray
    columns: int
    angles_from: str
    beam_origin_mm: float | None = None
    columns_from: str = "metadata"
    notes: tuple[str, ...] = field(default=())

    @property
    def beams(self) -> int:
        """Number of beams (rows of the range image, H)."""
        return int(self.elevation.size)

    def describe(self) -> dict[str, str]:
        """The model as ``name: text`` lines for ``flic info``."""
        el = np.degrees(self.elevation)
        az = np.degrees(self.azimuth_offset)
        out = {
            "sensor": self.name,
            "beams x columns": f"{self.beams} x {self.columns} (columns from {self.columns_from})",
            "elevation": f"{el.min():+.2f} .. {el.max():+.2f} deg",
            "beam azimuth offsets": f"{az.min():+.2f} .. {az.max():+.2f} deg",
            "beam angles from": f"{self.angles_from} ({ANGLE_SOURCES[self.angles_from]})",
        }
        if self.beam_origin_mm is not None:
            out["beam origin offset"] = f"{self.beam_origin_mm:.3f} mm"
        for i, note in enumerate(self.notes):
            out[f"note {i + 1}"] = note
        return out


#: Reader options a format may take (``flic info / segment / benchmark --columns / --rows``):
#: what they mean, for the error that names a format that does not take one.
READER_OPTIONS = {
    "columns": "columns per revolution W of a cloud without firing index (PCD)",
    "rows": "beams of a cloud without ring field (PCD)",
    "return": "the return read of a dual-return profile, 1 or 2 (Ouster pcap)",
    "calibration": "a velodyne-decoder calibration file (Velodyne pcap; an HDL-64E needs one)",
}


def check_reader_options(
    path: Path, fmt: str, accepted: tuple[str, ...], options: dict[str, Any]
) -> dict[str, Any]:
    """The reader options given (None values dropped), checked: known, taken by the format,
    integers of at least 1 (columns at least 8), a calibration an existing file.

    Raises
    ------
    FlicInputError
        Naming the option and the formats that take it.
    """
    given = {k: v for k, v in options.items() if v is not None}
    for key, value in given.items():
        if key not in READER_OPTIONS:
            raise FlicInputError(path, f"unknown reader option {key!r}")
        if key not in accepted:
            raise FlicInputError(
                path, f"--{key} ({READER_OPTIONS[key]}) does not apply to {fmt} data"
            )
        if key == "calibration":
            if not Path(value).is_file():
                raise FlicInputError(value, "(--calibration) is no file")
            continue
        low = 8 if key == "columns" else 1
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise FlicInputError(path, f"--{key} must be an integer >= {low}, not {value!r}")
    return given


@dataclass
class FileInfo:
    """What a sensor reader found in one recording (for ``refs`` and ``flic info``).

    Attributes
    ----------
    path : the recording.
    frames : number of complete revolutions (the frames ``--frames`` counts, from 0).
    sensor : its sensor model.
    points : (frames,) points (valid returns) per frame, where known at opening; else None.
    partial : incomplete revolutions left out (the start or end of a recording), with their
        points, e.g. ``["remainder of 2,603 points"]``.
    state : what the reader needs to load a frame again (picklable).
    label_paths : (frames,) label file per frame, or None.
    """

    path: Path
    frames: int
    sensor: SensorModel
    points: np.ndarray | None = None
    partial: list[str] = field(default_factory=list)
    state: object = None
    label_paths: list[Path | None] | None = None


class SensorFileDataset:
    """Base of the sensor-recording formats: a recording file, or a folder of them.

    A subclass sets ``format`` and ``suffixes``, implements ``_open(path) -> FileInfo`` (read
    the recording once, find its revolutions) and ``_load(info, k) -> Frame``. The sequence name
    of a recording is its file name without suffix; its frames are numbered 0, 1, ... in the
    file (``FrameRef.frame`` and ``FrameRef.index`` both). Predictions are written as
    SemanticKITTI ``.label`` files, one value per point of the frame as the reader gives it
    (``<out>/sequences/<name>/predictions/NNNNNN.label``).
    """

    format = ""
    suffixes: tuple[str, ...] = ()
    #: The reader options (:data:`READER_OPTIONS`) this format takes.
    reader_options: tuple[str, ...] = ()
    #: ``flic segment --semantics`` is for SemanticKITTI scans (its oracle reads ``.label``
    #: files); the sensor formats' predictions carry cluster ids only.
    point_semantics = False

    def __init__(
        self,
        root: str | Path,
        sequences: list[str] | None = None,
        frames: tuple[int | None, int | None] | None = None,
        require_labels: bool = False,
        **options: Any,
    ) -> None:
        from flic_cli.io.base import FrameRef, frames_text, in_frames, select_sequences

        self.root = Path(root)
        self.options = check_reader_options(self.root, self.format, self.reader_options, options)
        files = self._files(self.root)
        if not files:
            raise FlicInputError(self.root, f"holds no {self.format} recording")
        found: dict[str, Path] = {}
        for f in files:
            found.setdefault(self.sequence_name(f), f)
        found = select_sequences(self.root, found, sequences)
        self.infos: dict[str, FileInfo] = {}
        self._refs: list[FrameRef] = []
        for name, path in found.items():
            info = self._open(path)
            self.infos[name] = info
            for k in range(info.frames):
                if not in_frames(k, frames):
                    continue
                label = info.label_paths[k] if info.label_paths else None
                if require_labels and label is None:
                    raise FlicInputError(path, "has no ground-truth labels for its frames")
                self._refs.append(FrameRef(name, k, path, label, self.format, index=k))
        if not self._refs:
            what = "" if frames is None else f" in frames {frames_text(frames)}"
            raise FlicInputError(self.root, f"has no complete frame{what}")

    @classmethod
    def sequence_name(cls, path: Path) -> str:
        """The recording's name: the file name without its format suffix."""
        name = path.name
        for suffix in sorted(cls.suffixes, key=len, reverse=True):
            if name.lower().endswith(suffix):
                return name[: -len(suffix)]
        return path.stem

    @classmethod
    def accepts(cls, path: Path) -> bool:
        """True for a file this format reads (by its name and content)."""
        return path.is_file() and path.name.lower().endswith(cls.suffixes)

    @classmethod
    def _files(cls, root: Path) -> list[Path]:
        if root.is_file():
            return [root] if cls.accepts(root) else []
        if root.is_dir():
            return sorted(p for p in root.iterdir() if cls.accepts(p))
        return []

    @classmethod
    def detect(cls, path: Path) -> bool:
        """True when ``path`` is a recording of this format or a folder holding some."""
        try:
            return bool(cls._files(Path(path)))
        except OSError:
            return False

    def _open(self, path: Path) -> FileInfo:  # pragma: no cover - abstract
        raise NotImplementedError

    def _load(self, info: FileInfo, k: int):  # noqa: ANN202  # pragma: no cover - abstract
        raise NotImplementedError

    def refs(self) -> list:
        """Every selected frame, ordered by recording then frame number."""
        return list(self._refs)

    def labelled(self) -> bool:
        """Whether some selected frame has ground-truth labels (nuScenes with a Panoptic
        nuScenes ``.npz``; the other sensor formats have none)."""
        return any(r.label_path is not None for r in self._refs)

    def folders(self) -> list[Path]:
        """Where the input lies (outputs must not go inside it): the folder of recordings DATA
        names, or, for a single recording file, the file itself (so that ``--out`` may be a
        folder beside it)."""
        if self.root.is_file():
            return [self.root]
        return sorted({r.path.parent for r in self._refs})

    def sensor(self, ref) -> SensorModel:  # noqa: ANN001
        """The sensor model of a frame's recording."""
        return self.infos[ref.sequence].sensor

    def load(self, ref):  # noqa: ANN001, ANN201
        """Read one frame (a :class:`flic_cli.io.base.Frame` with its sensor range image)."""
        return self._load(self.infos[ref.sequence], ref.index)

    #: ``<out>/sequences/<recording>/predictions/<frame:06d>.label``: cluster ids, one per
    #: point of the frame as read; exports in the same layout.
    write_prediction = staticmethod(write_cluster_prediction)
    export_path = staticmethod(export_path)

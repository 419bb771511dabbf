"""Reading and writing the data formats: SemanticKITTI, Moosmann logs, predictions.

:func:`open_dataset` recognises the format of a folder and returns a :class:`Dataset`;
:func:`parse_frames` and :func:`parse_sequences` turn command-line selections into its arguments.
"""

from __future__ import annotations

import re
from pathlib import Path

from flic_cli.errors import FlicInputError
from flic_cli.io.atomic import atomic_write, atomic_write_bytes
from flic_cli.io.base import Dataset, Frame, FrameRef
from flic_cli.io.moosmann import (
    ImgCfg,
    MoosmannDataset,
    read_img_cfg,
    read_png_range,
    write_img_cfg,
    write_png_range,
)
from flic_cli.io.semantickitti import (
    Scan,
    SemanticKittiDataset,
    predictions_path,
    read_bin,
    read_calib,
    read_label,
    read_poses,
    read_predictions,
    read_scan,
    write_bin,
    write_calib,
    write_label,
    write_poses,
    write_predictions,
    write_times,
)
from flic_cli.registry import FORMATS as _FORMATS
from flic_cli.registry import load_all

#: Dataset format classes by name (from :data:`flic_cli.registry.FORMATS`), tried in this order.
FORMATS: dict[str, type] = load_all(_FORMATS)

__all__ = [
    "FORMATS",
    "Dataset",
    "Frame",
    "FrameRef",
    "ImgCfg",
    "MoosmannDataset",
    "Scan",
    "SemanticKittiDataset",
    "atomic_write",
    "atomic_write_bytes",
    "open_dataset",
    "parse_frames",
    "parse_sequences",
    "predictions_path",
    "read_bin",
    "read_calib",
    "read_img_cfg",
    "read_label",
    "read_png_range",
    "read_poses",
    "read_predictions",
    "read_scan",
    "write_bin",
    "write_calib",
    "write_img_cfg",
    "write_label",
    "write_png_range",
    "write_poses",
    "write_predictions",
    "write_times",
]


def open_dataset(
    path: str | Path,
    sequences: list[str] | None = None,
    frames: tuple[int | None, int | None] | None = None,
    require_labels: bool = False,
) -> Dataset:
    """Open a SemanticKITTI root or sequence, a Moosmann log or a folder of Moosmann logs.

    Parameters
    ----------
    path : the folder.
    sequences : sequences (SemanticKITTI ``"00"``) or log folder names to use; None = all.
    frames : ``(start, stop)`` frame numbers, start inclusive, stop exclusive, None = open.
    require_labels : fail unless every selected frame has ground-truth labels (Moosmann logs
        have none).

    Raises
    ------
    FlicInputError
        When the folder does not exist, is of no known format, or the selection is empty.
    """
    path = Path(path)
    if not path.exists():
        raise FlicInputError(path, "does not exist")
    for cls in FORMATS.values():
        if cls.detect(path):
            return cls(path, sequences, frames, require_labels)
    raise FlicInputError(path, "is none of: " + "; ".join(e.summary for e in _FORMATS.values()))


_FRAMES = re.compile(r"([0-9]*):([0-9]*)|([0-9]+)")


def parse_frames(text: str) -> tuple[int | None, int | None]:
    """Parse a frame selection.

    ``"10:20"`` -> ``(10, 20)`` (stop exclusive), ``"10:"`` -> ``(10, None)``,
    ``":20"`` -> ``(None, 20)``, ``"7"`` -> ``(7, 8)`` (one frame).

    Raises
    ------
    FlicInputError
        On anything else, or an empty range (start >= stop).
    """
    m = _FRAMES.fullmatch(text.strip())
    if m is None:
        raise FlicInputError(
            None, f"invalid frame range {text!r}: expected START:STOP, START:, :STOP or FRAME"
        )
    if m.group(3) is not None:
        return int(m.group(3)), int(m.group(3)) + 1
    start = int(m.group(1)) if m.group(1) else None
    stop = int(m.group(2)) if m.group(2) else None
    if start is not None and stop is not None and start >= stop:
        raise FlicInputError(None, f"empty frame range {text!r}: start must be below stop")
    return start, stop


def parse_sequences(text: str) -> list[str]:
    """Parse a comma-separated sequence list: ``"00,5"`` -> ``["00", "05"]``.

    Numbers are zero-padded to two digits (SemanticKITTI); other names (Moosmann log folders) are
    kept as they are. Duplicates are dropped.

    Raises
    ------
    FlicInputError
        When a name is empty.
    """
    names: list[str] = []
    for item in text.split(","):
        name = item.strip()
        if not name:
            raise FlicInputError(None, f"invalid sequence list {text!r}: empty name")
        name = f"{int(name):02d}" if name.isascii() and name.isdigit() else name
        if name not in names:
            names.append(name)
    return names

"""Reading and writing the data formats: SemanticKITTI, Moosmann logs, predictions.

:func:`open_dataset` recognises the format of a folder among those of
:data:`flic_cli.registry.FORMATS` and returns a :class:`Dataset`; :func:`parse_frames` and
:func:`parse_sequences` turn command-line selections into its arguments. No format module is
imported before it is needed: the formats' own functions (``read_bin``, ``read_img_cfg``, ...)
are importable from here and load their module on first use.
"""

from __future__ import annotations

import importlib
import re
from pathlib import Path
from typing import Any

from flic_cli import registry
from flic_cli.errors import FlicInputError
from flic_cli.io.atomic import atomic_write, atomic_write_bytes
from flic_cli.io.base import Dataset, Frame, FrameRef

#: What ``from flic_cli.io import NAME`` gives for the formats' own functions, imported from the
#: format's module on first use only (so ``import flic_cli.io`` imports no format).
_LAZY: dict[str, str] = {
    **dict.fromkeys(
        ("ImgCfg", "MoosmannDataset", "read_img_cfg", "read_png_range", "write_img_cfg",
         "write_png_range"),
        "flic_cli.io.moosmann",
    ),
    **dict.fromkeys(
        ("Scan", "SemanticKittiDataset", "predictions_path", "read_bin", "read_calib",
         "read_label", "read_poses", "read_predictions", "read_scan", "write_bin", "write_calib",
         "write_label", "write_poses", "write_predictions", "write_times"),
        "flic_cli.io.semantickitti",
    ),
}  # fmt: skip

__all__ = [
    "Dataset",
    "Frame",
    "FrameRef",
    "atomic_write",
    "atomic_write_bytes",
    "format_class",
    "open_dataset",
    "parse_frames",
    "parse_sequences",
    *_LAZY,
]


def __getattr__(name: str) -> Any:
    """A format's function or class, imported from its module on first use (see :data:`_LAZY`)."""
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


def format_class(name: str) -> type:
    """The dataset class of registered format ``name``, its optional package checked first.

    Raises
    ------
    FlicInputError
        When the format is unknown, or needs an optional package that is missing (with the
        install hint).
    """
    entry = registry.FORMATS.get(name)
    if entry is None:
        raise FlicInputError(
            None, f"unknown data format {name!r} (known: {', '.join(registry.FORMATS)})"
        )
    registry.check_installed(f"data format {name!r}", entry)
    cls = registry.load(entry)
    check = getattr(cls, "check_installed", None)
    if check is not None:
        check()
    return cls


def open_dataset(
    path: str | Path,
    sequences: list[str] | None = None,
    frames: tuple[int | None, int | None] | None = None,
    require_labels: bool = False,
    reader: dict[str, Any] | None = None,
) -> Dataset:
    """Open a SemanticKITTI root or sequence, a Moosmann log or a folder of Moosmann logs.

    Parameters
    ----------
    path : the folder.
    sequences : sequences (SemanticKITTI ``"00"``) or log folder names to use; None = all.
    frames : ``(start, stop)`` frame numbers, start inclusive, stop exclusive, None = open.
    require_labels : fail unless every selected frame has ground-truth labels (Moosmann logs
        have none).
    reader : reader options, e.g. ``{"columns": 1800, "rows": 16}`` for a PCD without ring
        field (:data:`flic_cli.io.sensor.READER_OPTIONS`); None values are left out.

    Raises
    ------
    FlicInputError
        When the folder does not exist, is of no known format, or the selection is empty.
    """
    path = Path(path)
    if not path.exists():
        raise FlicInputError(path, "does not exist")
    unavailable = []
    for name, entry in registry.FORMATS.items():
        if entry.missing() is not None:  # cannot be told apart without its package
            unavailable.append(f"{name} {entry.missing()}")
            continue
        cls = format_class(name)
        if cls.detect(path):
            options = {k: v for k, v in (reader or {}).items() if v is not None}
            if options and not hasattr(cls, "reader_options"):
                key = next(iter(options))
                raise FlicInputError(path, f"--{key} does not apply to {name} data")
            return cls(path, sequences, frames, require_labels, **options)
    known = "; ".join(e.summary for e in registry.FORMATS.values() if e.missing() is None)
    more = f" (not tried: {'; '.join(unavailable)})" if unavailable else ""
    raise FlicInputError(path, f"is none of: {known}{more}")


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

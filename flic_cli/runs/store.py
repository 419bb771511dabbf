"""The resumable store of a long run: one small CSV per frame and record kind, and ``run.json``.

Each finished frame is written to ``<out>/parts/<seq>/<frame>.<kind>.csv`` for each record kind
(e.g. ``objects``, then ``frames``), each file atomically, the ``frames`` file last: a frame is
done once its ``frames`` file exists. ``<out>/run.json`` holds the run's parameters; ``--resume``
continues a run with the same parameters and skips its done frames. :func:`read_parts` gathers the
parts of chosen frames into one DataFrame, in the order given, so that tables do not depend on the
order frames finished in, on ``--jobs`` or on interruptions.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

import pandas as pd

from flic_cli.errors import FlicInputError
from flic_cli.io.atomic import atomic_write

PARTS = "parts"
RUN_FILE = "run.json"

#: The record kind whose file marks a frame as done (written last).
DONE_KIND = "frames"

#: Frames read per chunk when parts are gathered (memory holds the compact table only).
_CHUNK_FRAMES = 2000


def part_path(parts: Path, sequence: str, frame: int, kind: str) -> Path:
    """``<parts>/<sequence>/<frame:06d>.<kind>.csv``."""
    return parts / sequence / f"{frame:06d}.{kind}.csv"


def write_part(
    parts: Path,
    sequence: str,
    frame: int,
    tables: dict[str, tuple[tuple[str, ...], dict[str, list]]],
) -> None:
    """Store one frame's records: ``tables[kind] = (columns, column lists)``, done-marker last."""
    kinds = sorted(tables, key=lambda k: k == DONE_KIND)
    for kind in kinds:
        columns, rows = tables[kind]
        with atomic_write(part_path(parts, sequence, frame, kind)) as tmp:
            with open(tmp, "w", newline="", encoding="utf-8") as f:
                writer = csv.writer(f, lineterminator="\n")
                writer.writerow(columns)
                writer.writerows(zip(*(rows[c] for c in columns), strict=True))


def done_frames(parts: Path, kinds: tuple[str, ...] = ()) -> set[tuple[str, int]]:
    """``(sequence, frame)`` of every frame whose parts are complete.

    Parameters
    ----------
    parts : the parts folder.
    kinds : the record kinds every done frame must have besides :data:`DONE_KIND`; a frame
        that lacks one (a part deleted by hand) is not done, and its remaining parts are
        removed, so that ``--resume`` computes it again.
    """
    done = set()
    for path in parts.glob(f"*/*.{DONE_KIND}.csv"):
        stem = path.name.split(".", 1)[0]
        if stem.isascii() and stem.isdigit():
            sequence, frame = path.parent.name, int(stem)
            if all(part_path(parts, sequence, frame, k).is_file() for k in kinds):
                done.add((sequence, frame))
            else:
                for k in (*kinds, DONE_KIND):
                    part_path(parts, sequence, frame, k).unlink(missing_ok=True)
    return done


def _clean_temporaries(parts: Path) -> None:
    """Remove temporary files that a killed run left behind."""
    for path in parts.glob("*/.*.tmp-*"):
        path.unlink(missing_ok=True)


def read_parts(
    parts: Path,
    keys: list[tuple[str, int]],
    kind: str,
    columns: tuple[str, ...],
    dtypes: dict[str, Any],
) -> pd.DataFrame:
    """Gather the ``kind`` parts of ``keys`` (in that order) into one DataFrame.

    Read in chunks of frames with fixed (categorical) dtypes, so that memory holds the compact
    table only, never the text of all parts at once.

    Raises
    ------
    FlicInputError
        When a part is missing, unreadable, corrupt (not UTF-8, cut short, a line of the wrong
        length or value type) or written by a version with other columns.
    """
    header = ",".join(columns) + "\n"
    chunks = []
    for start in range(0, len(keys), _CHUNK_FRAMES):
        text = [header]
        for sequence, frame in keys[start : start + _CHUNK_FRAMES]:
            path = part_path(parts, sequence, frame, kind)
            try:
                content = path.read_text(encoding="utf-8")
            except OSError:
                raise FlicInputError(
                    path, "part file is missing or unreadable (rerun with --resume)"
                ) from None
            except UnicodeDecodeError:
                raise FlicInputError(path, _CORRUPT + "it is not UTF-8 text") from None
            if not content.endswith("\n"):  # parts end with a line end: this one was cut
                raise FlicInputError(path, _CORRUPT + "it ends in the middle of a line")
            first, _, body = content.partition("\n")
            if first + "\n" != header:
                raise FlicInputError(
                    path,
                    "part file has other columns than this version of flic writes; "
                    "delete the parts folder or use another --out",
                )
            text.append(body)
        try:
            chunk = pd.read_csv(io.StringIO("".join(text)), dtype=dtypes, keep_default_na=False)
        except (ValueError, pd.errors.ParserError) as exc:  # find the part that breaks it
            for sequence, frame in keys[start : start + _CHUNK_FRAMES]:
                _check_part(part_path(parts, sequence, frame, kind), header, dtypes)
            raise FlicInputError(
                parts,
                f"part files of kind {kind} do not parse ({exc}): delete them and rerun with "
                "--resume",
            ) from None
        chunks.append(chunk)
    if not chunks:
        return pd.DataFrame({c: pd.Series(dtype=dtypes.get(c, "float64")) for c in columns})
    return pd.concat(chunks, ignore_index=True)


_CORRUPT = "part file is corrupt (delete it and rerun with --resume: its frame is computed again): "


def _check_part(path: Path, header: str, dtypes: dict[str, Any]) -> None:
    """Raise :class:`FlicInputError` naming ``path`` when it does not parse as a part file."""
    text = path.read_text(encoding="utf-8")
    n_columns = header.count(",") + 1
    for lineno, line in enumerate(text.splitlines()[1:], start=2):
        if line.count(",") + 1 != n_columns:
            raise FlicInputError(
                path, _CORRUPT + f"line {lineno} has {line.count(',') + 1} of {n_columns} fields"
            )
    try:
        pd.read_csv(io.StringIO(text), dtype=dtypes, keep_default_na=False)
    except (ValueError, pd.errors.ParserError) as exc:
        raise FlicInputError(path, _CORRUPT + str(exc).splitlines()[0]) from None


def _differences(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    return sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))


def open_store(
    out: Path, params: dict[str, Any], resume: bool, kinds: tuple[str, ...] = ()
) -> set[tuple[str, int]]:
    """Check ``out`` against an earlier run, write ``run.json``; return the frames already done.

    ``kinds``: the record kinds a done frame must have (see :func:`done_frames`).

    Raises
    ------
    FlicInputError
        When ``out`` holds parts of an earlier run and ``resume`` is false, or of a run with other
        parameters.
    """
    parts = out / PARTS
    run_file = out / RUN_FILE
    has_parts = parts.is_dir() and any(parts.glob("*/*.csv"))
    old = None
    if run_file.is_file():
        try:
            old = json.loads(run_file.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            old = None
        if not isinstance(old, dict):  # JSON, but not a run's parameters ([1], "x", 3)
            old = None
    if has_parts:
        if old is None:
            raise FlicInputError(
                parts,
                "holds per-frame results of an unknown run (no valid run.json); use another --out",
            )
        diff = _differences(old, params)
        if diff:
            raise FlicInputError(
                out,
                f"holds results of a different run ({', '.join(diff)} differ); "
                "use another --out, or repeat that run's options with --resume",
            )
        if not resume:
            raise FlicInputError(
                out,
                "holds results of this run already: add --resume to continue it "
                "(finished frames are kept), or use another --out",
            )
        _clean_temporaries(parts)
        return done_frames(parts, kinds)
    with atomic_write(run_file) as tmp:
        tmp.write_text(json.dumps(params, indent=2, sort_keys=True) + "\n", encoding="utf-8")
    return set()

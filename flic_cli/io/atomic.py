"""File access with one-line errors: atomic writes and checked reads.

Every writer of the project goes through :func:`atomic_write`, so that an interrupted or failing
write never leaves a half-written file behind: the data goes to a temporary file in the target's
folder and is renamed over the target only once it is complete.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from flic_cli.errors import FlicInputError

if TYPE_CHECKING:
    import pandas as pd


@contextmanager
def atomic_write(path: str | Path) -> Iterator[Path]:
    """Write a file atomically.

    Yields a temporary path ``.<name>.tmp-<pid>`` in the target's folder; the caller writes the
    complete file there. On success it is renamed over ``path`` (:func:`os.replace`); on an
    exception it is removed and the exception propagates.

    Parameters
    ----------
    path : the file to write; missing parent folders are created.

    Raises
    ------
    FlicInputError
        When the folder cannot be created or written to.
    """
    path = Path(path)
    folder = path.parent
    tmp = folder / f".{path.name}.tmp-{os.getpid()}"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tmp.touch()
    except OSError:
        raise FlicInputError(folder, "output folder is not writable") from None
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def atomic_write_bytes(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_write`)."""
    with atomic_write(path) as tmp:
        tmp.write_bytes(data)


def read_bytes(path: str | Path) -> bytes:
    """The content of a file; :class:`FlicInputError` when it is missing or unreadable."""
    try:
        return Path(path).read_bytes()
    except FileNotFoundError:
        raise FlicInputError(path, "does not exist") from None
    except OSError as exc:
        raise FlicInputError(path, f"cannot be read ({exc.strerror})") from None


def read_text(path: str | Path) -> str:
    """The content of a UTF-8 text file; :class:`FlicInputError` when missing or unreadable."""
    try:
        return read_bytes(path).decode("utf-8")
    except UnicodeDecodeError:
        raise FlicInputError(path, "is not a UTF-8 text file") from None


@contextmanager
def staged_folder(out: str | Path) -> Iterator[Path]:
    """Write a run's many output files so that a failed run leaves none of them.

    Yields a temporary folder beside ``out`` (same file system) to write into; when the block
    succeeds, every file in it is moved to the same place under ``out`` (replacing files of an
    earlier run), and the temporary folder is removed. When the block fails, the temporary folder
    is removed and ``out`` is left as it was.

    Raises
    ------
    FlicInputError
        When the folder beside ``out`` cannot be written.
    """
    out = Path(out).resolve()
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.staging-", dir=out.parent))
    except OSError:
        raise FlicInputError(out.parent, "output folder is not writable") from None
    try:
        yield tmp
        for src in sorted(p for p in tmp.rglob("*") if p.is_file()):
            dst = out / src.relative_to(tmp)
            dst.parent.mkdir(parents=True, exist_ok=True)
            os.replace(src, dst)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def write_table(path: str | Path, table: pd.DataFrame) -> Path:
    """Write a table as CSV (no index column) atomically; missing parent folders are created.

    Returns
    -------
    The written file.
    """
    with atomic_write(path) as tmp:
        table.to_csv(tmp, index=False)
    return Path(path)

"""File access with one-line errors: atomic writes and checked reads.

Every writer of the project goes through :func:`atomic_write`, so that an interrupted or failing
write never leaves a half-written file behind: the data goes to a temporary file in the target's
folder and is renamed over the target only once it is complete.
"""

from __future__ import annotations

import errno
import os
import re
import shutil
import stat
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO

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
    except OSError as exc:
        why = f": {exc.strerror}" if exc.errno in _FULL else ""
        raise FlicInputError(folder, f"output folder is not writable{why}") from None
    try:
        yield tmp
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        if exc.errno in _FULL:
            raise FlicInputError(path, f"cannot be written: {os.strerror(exc.errno)}") from None
        raise
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


#: ``errno`` values of a full disk or an exhausted quota: bad input (the output place), not a bug.
_FULL = {errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC), errno.EFBIG}


def atomic_write_bytes(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_write`)."""
    with atomic_write(path) as tmp:
        tmp.write_bytes(data)


def open_regular(path: str | Path) -> BinaryIO:
    """Open a file for reading (unbuffered, binary), refusing anything but a regular file.

    A FIFO, a socket or a device where a file is expected would block the run forever (or read
    without end): the file is opened without blocking and checked (``stat.S_ISREG``) before
    anything is read.

    Raises
    ------
    FlicInputError
        When ``path`` is a FIFO, a device or a socket.
    OSError
        When it is missing, a folder (IsADirectoryError) or cannot be opened.
    """
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    try:
        mode = os.fstat(fd).st_mode
        if stat.S_ISDIR(mode):  # the callers' "cannot be read (Is a directory)"
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        if not stat.S_ISREG(mode):
            raise FlicInputError(path, f"is {_file_kind(mode)}, not a regular file")
        if hasattr(os, "O_NONBLOCK"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb", buffering=0)
    except BaseException:
        os.close(fd)
        raise


def _file_kind(mode: int) -> str:
    """``a FIFO``, ``a character device``, ... of an ``st_mode``."""
    kinds = (
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    )
    return next((name for test, name in kinds if test(mode)), "a special file")


def read_bytes(path: str | Path) -> bytes:
    """The content of a regular file; :class:`FlicInputError` when it is missing, unreadable or
    not a regular file (see :func:`open_regular`)."""
    try:
        with open_regular(path) as f:
            return f.read()
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
        remove_stale_staging(out)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.staging-", dir=out.parent))
    except OSError:
        raise FlicInputError(out.parent, "output folder is not writable") from None
    try:
        yield tmp
        for src in sorted(p for p in tmp.rglob("*") if p.is_file()):
            dst = out / src.relative_to(tmp)
            dst.parent.mkdir(parents=True, exist_ok=True)
            os.replace(src, dst)
    except OSError as exc:
        if exc.errno in _FULL:
            raise FlicInputError(out, f"cannot be written: {os.strerror(exc.errno)}") from None
        raise
    except FlicInputError as exc:  # name the output as the user knows it, not the staging name
        if exc.path is None or not exc.path.resolve().is_relative_to(tmp.resolve()):
            raise
        inside = exc.path.resolve().relative_to(tmp.resolve())
        raise FlicInputError(out / inside, exc.reason) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def remove_stale_staging(out: str | Path) -> list[Path]:
    """Remove the staging folders that killed runs into ``out`` left beside it.

    Only names :func:`staged_folder` makes for this ``out`` are touched
    (``.<name>.staging-`` and the 8 characters of :func:`tempfile.mkdtemp`). Call it while
    holding ``out``'s lock (:func:`locked_folder`): then no other run is writing into them.

    Returns
    -------
    The folders removed.
    """
    out = Path(out).resolve()
    pattern = re.compile(rf"\.{re.escape(out.name)}\.staging-[A-Za-z0-9_]{{8}}")
    removed = []
    if out.parent.is_dir():
        for path in out.parent.iterdir():
            if pattern.fullmatch(path.name) and path.is_dir() and not path.is_symlink():
                shutil.rmtree(path, ignore_errors=True)
                removed.append(path)
    return removed


@contextmanager
def locked_folder(out: str | Path) -> Iterator[Path]:
    """Hold an exclusive lock on the output folder ``out`` for the duration of a run.

    The lock is :func:`fcntl.flock` on the folder itself (no lock file is left behind); the
    kernel releases it when the process ends in whatever way, a crash or SIGKILL included. The
    folders made here for the lock are removed again when the run leaves them empty.

    Raises
    ------
    FlicInputError
        When another process (another flic run) holds the lock, or the folder cannot be made.
    """
    import fcntl

    out = Path(out)
    made = [p for p in (out, *out.parents) if not p.exists()]  # to remove again if left empty
    try:
        out.mkdir(parents=True, exist_ok=True)
        fd = os.open(out, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | os.O_CLOEXEC)
    except OSError as exc:
        raise FlicInputError(out, f"output folder cannot be made ({exc.strerror})") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise FlicInputError(
                out,
                "is the output folder of another flic run that is still going: wait for it to "
                "end, or use another --out",
            ) from None
        yield out
    finally:
        os.close(fd)
        for folder in made:  # only when empty: the run failed before writing anything
            try:
                folder.rmdir()
            except OSError:
                break


def write_table(path: str | Path, table: pd.DataFrame) -> Path:
    """Write a table as CSV (no index column) atomically; missing parent folders are created.

    Returns
    -------
    The written file.
    """
    with atomic_write(path) as tmp:
        table.to_csv(tmp, index=False)
    return Path(path)

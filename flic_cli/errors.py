"""Errors that the command line reports as one line, without a traceback."""

from __future__ import annotations

import sys
from pathlib import Path


class FlicInputError(Exception):
    """Bad input: a file or folder that cannot be used, and why.

    The CLI prints ``error: <path>: <reason>`` and exits with code 2.
    """

    def __init__(self, path: str | Path | None, reason: str) -> None:
        self.path = None if path is None else Path(path)
        self.reason = reason
        super().__init__(f"{self.path}: {reason}" if self.path is not None else reason)


def print_warning(text: str) -> None:
    """Print ``warning: <text>`` to stderr on a line of its own, above any progress bar.

    Every warning flic shows goes through here (see :func:`show_warning`); its text starts with
    the file it is about.
    """
    from tqdm import tqdm

    tqdm.write(f"warning: {text}", file=sys.stderr)


def show_warning(message: Warning | str, *_: object, **__: object) -> None:
    """A :data:`warnings.showwarning` that prints ``warning: <message>`` (no source line)."""
    print_warning(str(message))

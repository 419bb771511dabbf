"""Errors that the command line reports as one line, without a traceback."""

from __future__ import annotations

from pathlib import Path


class FlicInputError(Exception):
    """Bad input: a file or folder that cannot be used, and why.

    The CLI prints ``error: <path>: <reason>`` and exits with code 2.
    """

    def __init__(self, path: str | Path | None, reason: str) -> None:
        self.path = None if path is None else Path(path)
        self.reason = reason
        super().__init__(f"{self.path}: {reason}" if self.path is not None else reason)

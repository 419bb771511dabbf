"""Checks on an output folder, done before any work so that a run never fails at its end."""

from __future__ import annotations

import functools
import inspect
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from flic_cli.errors import FlicInputError
from flic_cli.io.atomic import locked_folder

F = TypeVar("F", bound=Callable[..., Any])


def check_output_dir(out: Path, inputs: list[Path] | tuple[Path, ...] = ()) -> Path:
    """Make sure ``out`` can become the run's output folder.

    Nothing is created: the folder is made when the first output is written.

    Parameters
    ----------
    out : the output folder (``--out``).
    inputs : folders of the input data that outputs must not go into (a sequence folder or a
        Moosmann log: writing inside them would nest ``sequences/NN/`` in the data).

    Raises
    ------
    FlicInputError
        When ``out`` is an existing file, lies inside one of ``inputs``, or neither it nor the
        folder that would hold it can be written.
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise FlicInputError(out, "is an existing file, expected an output folder (--out)")
    resolved = out.resolve()
    for folder in inputs:
        folder = Path(folder).resolve()
        if resolved == folder or folder in resolved.parents:
            raise FlicInputError(
                out, f"lies inside the input data {folder}: choose an output folder outside it"
            )
    probe = resolved
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        raise FlicInputError(out, f"cannot be created: {probe} is a file")
    if not os.access(probe, os.W_OK | os.X_OK):
        what = "is not writable" if probe == resolved else f"cannot be created in {probe}"
        raise FlicInputError(out, f"output folder {what} (permission denied)")
    return out


def holding_out_lock(func: F) -> F:
    """Run ``func`` (a run with an ``out`` parameter, or a ``spec`` with an ``out`` field)
    holding the lock of its output folder.

    Two runs into one ``--out`` would mix their results: the second is refused with a one-line
    error while the first holds the lock (:func:`flic_cli.io.atomic.locked_folder`, released
    by the kernel however the process ends).
    """
    signature = inspect.signature(func)

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        arguments = signature.bind(*args, **kwargs).arguments
        out = Path(arguments["out"] if "out" in arguments else arguments["spec"].out)
        check_output_dir(out)
        with locked_folder(out):
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]

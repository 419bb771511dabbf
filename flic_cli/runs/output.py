"""Checks on an output folder, done before any work so that a run never fails at its end."""

from __future__ import annotations

import os
from pathlib import Path

from flic_cli.errors import FlicInputError


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

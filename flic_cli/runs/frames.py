"""The frame loop every command shares: one policy for bad frames, warnings and progress.

A run maps a per-frame function over the selected frames (in this process, in local processes or
on a dask cluster, see :mod:`flic_cli.runs.parallel`). :class:`FrameLoop` wraps that map so that
every command behaves the same:

- **Bad frames.** A frame whose input is bad (a corrupt ``.bin``, a broken PNG, a ``.label`` of
  the wrong length: any :class:`flic_cli.errors.FlicInputError`) stops the run with a one-line
  error naming the file. With ``skip_bad`` the run goes on instead; the skipped frames are
  counted and listed (:attr:`FrameLoop.skipped`, written as ``skipped.csv`` by the commands).
- **Warnings** raised while a frame is processed, in whichever process, come back to this process
  and are printed as ``warning: <file>: <message>`` on their own line, above the progress bar.
- **Progress**: one tqdm bar per run.
"""

from __future__ import annotations

import csv
import os
import sys
import warnings
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Generic, TypeVar

from tqdm import tqdm

from flic_cli.errors import FlicInputError, print_warning
from flic_cli.io.atomic import atomic_write
from flic_cli.io.base import FrameRef
from flic_cli.runs.parallel import imap_frames, jobs_note, resolve_jobs

R = TypeVar("R")

#: Columns of ``skipped.csv``.
SKIPPED_COLUMNS = ("sequence", "frame", "file", "reason")


@dataclass
class Outcome(Generic[R]):
    """What one frame gave: its value or its input error, and the warnings it raised."""

    ref: FrameRef
    value: R | None = None
    error: tuple[str | None, str] | None = None
    warnings: list[str] = field(default_factory=list)


class FrameTask(Generic[R]):
    """Picklable wrapper run in the worker: catches input errors and records warnings.

    Parameters
    ----------
    func : a top-level (picklable) function of a :class:`FrameRef`.
    """

    def __init__(self, func: Callable[[FrameRef], R]) -> None:
        self.func = func

    def __call__(self, ref: FrameRef) -> Outcome[R]:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                value = self.func(ref)
            except FlicInputError as exc:  # an error naming no file is about this frame's
                path = str(ref.path if exc.path is None else exc.path)
                return Outcome(ref, error=(path, exc.reason), warnings=_texts(caught, ref))
        return Outcome(ref, value, warnings=_texts(caught, ref))


def _texts(caught: list[warnings.WarningMessage], ref: FrameRef) -> list[str]:
    """Warning messages, each starting with a file (the frame's when the message names none)."""
    out = []
    for w in caught:
        text = str(w.message)
        head = text.split(": ", 1)[0]
        names_a_file = "/" in head or Path(head).suffix != ""
        out.append(text if names_a_file else f"{ref.path}: {text}")
    return list(dict.fromkeys(out))


@dataclass(frozen=True)
class Skipped:
    """A frame left out by ``--skip-bad``: which one, its file and why."""

    sequence: str
    frame: int
    file: str
    reason: str

    def line(self) -> str:
        return f"{self.file}: {self.reason}"


class FrameLoop(Generic[R]):
    """Iterate ``(ref, value)`` of a per-frame function over frames, with the shared policy.

    Parameters
    ----------
    func : top-level (picklable) function of a :class:`FrameRef`; raises FlicInputError on bad
        input.
    refs : the frames to process.
    jobs, scheduler : where to run (see :func:`flic_cli.runs.parallel.imap_frames`).
    skip_bad : go on past bad frames (collected in :attr:`skipped`) instead of stopping.
    desc : progress bar label; ``progress=False`` hides the bar.
    initial, total : progress bar start and length (a resumed run starts past its done frames).

    Yields
    ------
    (FrameRef, value) in completion order (frame order with ``jobs=1``).

    Raises
    ------
    FlicInputError
        At the first bad frame unless ``skip_bad``: its file and what is wrong.
    """

    def __init__(
        self,
        func: Callable[[FrameRef], R],
        refs: Iterable[FrameRef],
        jobs: int = 1,
        scheduler: str | None = None,
        skip_bad: bool = False,
        desc: str = "",
        progress: bool = True,
        initial: int = 0,
        total: int | None = None,
    ) -> None:
        self.refs = list(refs)
        self.task = FrameTask(func)
        self.jobs = jobs
        self.scheduler = scheduler
        self.skip_bad = skip_bad
        self.desc = desc
        self.progress = progress
        self.initial = initial
        self.total = len(self.refs) + initial if total is None else total
        self.skipped: list[Skipped] = []

    def _outcomes(self) -> Iterator[Outcome[R]]:
        """The outcomes; on a fresh install (numba's cache empty) the first frame runs here,
        so that the kernels are compiled once and cached, not by every worker at the same time."""
        jobs = self.jobs
        if self.scheduler is None:
            note = jobs_note(jobs, len(self.refs))
            if note is not None and self.progress:
                tqdm.write(note, file=sys.stderr)
            jobs = resolve_jobs(jobs, len(self.refs))
        first = self.refs[:1] if jobs != 1 and not kernels_cached() else []
        yield from imap_frames(self.task, first, 1, None)
        if self.refs[len(first) :]:  # (no scheduler to contact for no frames)
            yield from imap_frames(self.task, self.refs[len(first) :], jobs, self.scheduler)

    def __iter__(self) -> Iterator[tuple[FrameRef, R]]:
        if self.progress and self.refs and not kernels_cached():
            tqdm.write(COMPILE_NOTE, file=sys.stderr)
        with tqdm(
            total=self.total,
            initial=self.initial,
            desc=self.desc,
            unit="frame",
            disable=not self.progress,
            file=sys.stderr,
        ) as bar:
            for k, outcome in enumerate(self._outcomes()):
                for text in outcome.warnings:
                    print_warning(text)
                if outcome.error is not None:
                    path, reason = outcome.error
                    if not self.skip_bad:
                        raise FlicInputError(path, reason)
                    file = path or str(outcome.ref.path)
                    self.skipped.append(
                        Skipped(outcome.ref.sequence, outcome.ref.frame, file, reason)
                    )
                    print_warning(f"{file}: {reason} (frame skipped: --skip-bad)")
                else:
                    yield outcome.ref, outcome.value  # type: ignore[misc]
                bar.update(1)
                if k == 0 and not bar.disable:
                    _restart_rate(bar)

    def note(self) -> str | None:
        """A summary line about skipped frames, or None when none was skipped."""
        if not self.skipped:
            return None
        return f"skipped {len(self.skipped)} bad frame(s) (--skip-bad), listed in skipped.csv"


#: Said before the first frame when numba's cache of flic's kernels is empty.
COMPILE_NOTE = (
    "note: first run of this installation: numba compiles flic's kernels during the first "
    "frame, about one to two minutes (once: they are cached for later runs)"
)


def kernels_cached() -> bool:
    """Whether numba's cache holds compiled kernels of flic (else the first frame compiles them).

    Looks for numba's index files (``*.nbi``) in ``NUMBA_CACHE_DIR`` when it is set (numba
    then caches there), else beside flic's modules.
    """
    import flic_cli

    place = Path(os.environ.get("NUMBA_CACHE_DIR") or Path(flic_cli.__file__).parent)
    return place.is_dir() and next(place.rglob("*.nbi"), None) is not None


def _restart_rate(bar: tqdm) -> None:
    """Start the bar's rate and ETA afresh after the first frame, which also loads (on a fresh
    install: compiles) the kernels and would make the estimate far too long."""
    n = bar.n
    bar.reset(bar.total)
    bar.initial = bar.n = bar.last_print_n = n
    bar.refresh()


def write_skipped(path: Path, skipped: list[Skipped]) -> Path:
    """Write the skipped frames as CSV (:data:`SKIPPED_COLUMNS`), atomically."""
    with atomic_write(path) as tmp:
        with open(tmp, "w", newline="", encoding="utf-8") as f:
            writer = csv.writer(f, lineterminator="\n")
            writer.writerow(SKIPPED_COLUMNS)
            writer.writerows((s.sequence, s.frame, s.file, s.reason) for s in skipped)
    return path


def sort_skipped(skipped: list[Skipped]) -> list[Skipped]:
    """Skipped frames in frame order (completion order depends on ``--jobs``)."""
    return sorted(skipped, key=lambda s: (s.sequence, s.frame))

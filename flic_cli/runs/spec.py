"""What a run is asked to do: one typed specification per command.

Every run works on a :class:`Selection` (the data, which part of it, in which setting, with which
config, how) and adds its own fields: :class:`SegmentRun`, :class:`EvaluateRun`,
:class:`BenchmarkRun`, :class:`SweepRun`, taken by :func:`flic_cli.runs.segment.run_segment`,
:func:`flic_cli.runs.evaluate.run_evaluate`, :func:`flic_cli.runs.benchmark.run_benchmark` and
:func:`flic_cli.runs.sweep.run_sweep`. The command line builds them from its options, the Python
API from its arguments.

Example
-------
>>> from pathlib import Path
>>> sel = Selection(Path("data/semantickitti"), sequences=["08"], frames=(0, 100), jobs=4)
>>> spec = EvaluateRun(sel, out=Path("eval"), methods=["flic0", "bogoslavskyi"])
>>> spec.selection.setting_or("both")
'both'
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from flic_cli.config.schema import Config


@dataclass(frozen=True)
class Selection:
    """The data a run works on, and how (what every command shares).

    Attributes
    ----------
    data : dataset root, sequence folder, log or recording (see :func:`flic_cli.io.open_dataset`).
    sequences : sequences (or logs) to use; None = all.
    frames : ``(start, stop)`` frame numbers, start inclusive, stop exclusive, None = open;
        None = all frames.
    setting : ``"ground"``, ``"no-ground"`` (or, for evaluate, ``"both"``); None = the command's
        default (segment and benchmark ``ground``, evaluate ``both``, sweep ``no-ground``).
    ground_remover : a remover's name or ``"own"`` (each method variant's own ``ground`` key,
        see :func:`flic_cli.runs.pipeline.build_segmenter`); None = the command's default (segment
        and benchmark ``own``, evaluate and sweep ``paper``, the paper's protocol).
    config : the loaded config (:func:`flic_cli.config.load_config`); None = the shipped presets.
    jobs : local worker processes (see :func:`flic_cli.runs.parallel.imap_frames`); benchmark
        always times in one process.
    skip_bad : go on past frames whose input is bad (listed in ``skipped.csv``).
    progress : show a progress bar.
    reader : reader options (``{"columns": W, "rows": H}``, see
        :data:`flic_cli.io.sensor.READER_OPTIONS`); None = none.
    """

    data: Path
    sequences: list[str] | None = None
    frames: tuple[int | None, int | None] | None = None
    setting: str | None = None
    ground_remover: str | None = None
    config: Config | None = None
    jobs: int = 1
    skip_bad: bool = False
    progress: bool = True
    reader: dict[str, object] | None = None

    def setting_or(self, default: str) -> str:
        """:attr:`setting`, or the command's ``default`` when None."""
        return default if self.setting is None else self.setting

    def remover_or(self, default: str) -> str:
        """:attr:`ground_remover`, or the command's ``default`` when None."""
        return default if self.ground_remover is None else self.ground_remover

    def loaded_config(self) -> Config:
        """:attr:`config`, or the shipped presets when None."""
        if self.config is not None:
            return self.config
        from flic_cli.config.parser import load_config

        return load_config()


@dataclass(frozen=True)
class SegmentRun:
    """``flic segment``: predictions of one method for every selected frame.

    Attributes
    ----------
    selection : the data and how.
    out : output root.
    method : method variant name (``flic14``, ``bogoslavskyi``, ...).
    render : also draw this frame number (which must be among the selected frames):
        ``<out>/render_<seq>_<frame>.png`` (the range image) and ``<out>/views_<seq>_<frame>.png``
        (bird's-eye and oblique 3D views; with labels, ground truth beside the prediction).
    semantics : ``"none"``, ``"oracle"`` (ground-truth classes) or a folder of a semantic
        network's predictions (``DIR/sequences/NN/predictions/XXXXXX.label``).
    export : per-frame exports besides the predictions: ``"ply"``.
    """

    selection: Selection
    out: Path
    method: str
    render: int | None = None
    semantics: str = "none"
    export: tuple[str, ...] = ()


@dataclass(frozen=True)
class EvaluateRun:
    """``flic evaluate``: the quality protocol over every selected labelled frame.

    Attributes
    ----------
    selection : the data and how (setting ``"no-ground"``, ``"ground"`` or ``"both"``).
    out : output folder (``parts/``, ``run.json`` and the tables).
    methods : method variant names of the config.
    scheduler : dask.distributed scheduler address, instead of local processes.
    resume : continue the run stored in ``out`` (same parameters), skipping its finished frames.
    skip_missing : evaluate only the frames that have labels instead of failing.
    semantics : ``"none"`` or ``"oracle"`` (also per class with ground-truth semantics).
    runtimes : a ``flic benchmark`` ``summary.csv`` whose median times go into
        ``quality_speed.csv`` instead of the times measured by this run.
    on_start : called with (frames selected, frames already done, frames without labels) before
        the work starts.
    on_estimate : called with a line estimating the run's duration before most of it starts.
    """

    selection: Selection
    out: Path
    methods: list[str]
    scheduler: str | None = None
    resume: bool = False
    skip_missing: bool = False
    semantics: str = "none"
    runtimes: Path | None = None
    on_start: Callable[[int, int, int], None] | None = field(default=None, compare=False)
    on_estimate: Callable[[str], None] | None = field(default=None, compare=False)


@dataclass(frozen=True)
class BenchmarkRun:
    """``flic benchmark``: per-frame runtime of every method.

    Attributes
    ----------
    selection : the data and how (``jobs`` is not used: timing runs in one process).
    out : output folder.
    methods : method variant names of the config.
    warmup : untimed runs of every method on the first frame.
    repeat : timed runs per frame and method, back to back; the median is kept.
    rounds : passes over the whole selection; each frame's median over the passes is kept.
    slow_every : methods declared ``slow`` run only on every n-th frame of the selection.
    threads : threads of numba and the native thread pools during the run.
    plots : write the PNG plots.
    """

    selection: Selection
    out: Path
    methods: list[str]
    warmup: int = 3
    repeat: int = 1
    rounds: int = 1
    slow_every: int = 10
    threads: int = 1
    plots: bool = True


@dataclass(frozen=True)
class SweepRun:
    """``flic sweep-threshold``: IoU_mu and P_mu against a method's main parameter.

    Attributes
    ----------
    selection : the data and how.
    out : output folder.
    method : method variant name.
    start, stop, step : the values (None: the method class's ``sweep_range``).
    scheduler : dask.distributed scheduler address, instead of local processes.
    skip_missing : leave out frames without labels instead of failing.
    """

    selection: Selection
    out: Path
    method: str
    start: float | None = None
    stop: float | None = None
    step: float | None = None
    scheduler: str | None = None
    skip_missing: bool = False

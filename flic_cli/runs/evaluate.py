"""``flic evaluate``: the paper's quality protocol (docs/specification.md) over a whole dataset.

The run, as a list of steps (:func:`run_evaluate`):

1. select the labelled frames and check the output folder;
2. build the segmenters once from the config (:mod:`flic_cli.runs.pipeline`);
3. open the resumable store in ``--out`` (:mod:`flic_cli.runs.store`): ``run.json`` and the
   frames an interrupted run already finished;
4. score the other frames, in parallel if asked (:class:`flic_cli.runs.scoring.ScoreJob` through
   :class:`flic_cli.runs.frames.FrameLoop`), storing each frame's records as it finishes;
5. gather the records of the selected frames and write every table
   (:mod:`flic_cli.runs.tables`), each atomically.

Outputs: ``table.csv`` (the paper's Table 1 layout), ``per_setting.csv``, ``per_sequence.csv``,
``by_class.csv``, ``by_distance.csv``, ``per_object.csv`` (one row per ground-truth object, method
and setting, IoU as a fraction), ``per_frame.csv`` (clusters, over- and under-segmentation and time
per frame, method and setting), ``skipped.csv`` with ``--skip-bad``; ``parts/`` and ``run.json``
for ``--resume``.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from flic_cli import registry
from flic_cli.config import Config
from flic_cli.errors import FlicInputError
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.io.base import Dataset, FrameRef
from flic_cli.runs.frames import FrameLoop, Skipped, sort_skipped, write_skipped
from flic_cli.runs.output import check_output_dir, holding_out_lock
from flic_cli.runs.parallel import SchedulerError, check_scheduler, resolve_jobs
from flic_cli.runs.pipeline import build_segmenters
from flic_cli.runs.scoring import (
    FRAME_COLUMNS,
    GROUND_COLUMNS,
    OBJECT_COLUMNS,
    PANOPTIC_COLUMNS,
    FrameScores,
    ScoreJob,
)
from flic_cli.runs.spec import EvaluateRun
from flic_cli.runs.store import PARTS, open_store, read_parts, write_part
from flic_cli.runs.tables import (
    all_tables,
    frame_dtypes,
    ground_dtypes,
    ground_lines,
    object_dtypes,
    panoptic_dtypes,
    shown_table,
)
from flic_cli.sensor_params import for_dataset

#: ``--setting`` of evaluate: one setting or both in one pass (each frame read once).
EVAL_SETTINGS: dict[str, tuple[str, ...]] = {
    "no-ground": ("no-ground",),
    "ground": ("ground",),
    "both": ("no-ground", "ground"),
}


#: Frames evaluated in this process first, timed, for the estimate of the whole run.
CALIBRATION_FRAMES = 3


def estimate_line(
    timing: list[tuple[float, FrameScores]], remaining: int, jobs: int, scheduler: str | None
) -> str:
    """How long the rest of a run takes: frames x measured cost per frame, per worker.

    Parameters
    ----------
    timing : (wall seconds, records) of each frame evaluated so far in this process.
    remaining : frames still to evaluate.
    jobs, scheduler : where they run (a dask cluster's size is not known here: the line gives
        the worker time to divide by it).
    """
    per_frame = float(np.median([t for t, _ in timing]))  # the median: the first frame
    methods: dict[str, list[float]] = {}  # also loads the compiled kernels
    for _, scores in timing:
        for name, seconds in zip(scores.frames["method"], scores.frames["seconds"], strict=True):
            methods.setdefault(name, []).append(seconds)
    methods = {m: [float(np.median(t)) * len(t) / len(timing)] for m, t in methods.items()}
    cost = {m: t[0] for m, t in methods.items()}
    # a method's seconds include its remover's mask, which is extracted once per frame and remover
    # (the ground records) and shared by the methods that use it
    ground = [sum(r.ground["seconds"]) for _, r in timing]
    methods_alone = [sum(r.frames["seconds"]) - sum(r.frames["ground_seconds"]) for _, r in timing]
    walls = [t for t, _ in timing]
    rest = [max(t - m - g, 0.0) for t, m, g in zip(walls, methods_alone, ground, strict=True)]
    other = float(np.median(rest))
    parts = ", ".join(f"{m} {_duration(t)}" for m, t in cost.items())
    if any(ground):
        parts += (
            f", each with its ground extraction; the ground extraction once per frame "
            f"{_duration(float(np.median(ground)))}"
        )
    total = per_frame * remaining
    line = (
        f"estimate from {len(timing)} frame(s): {_duration(per_frame)} per frame ({parts}; "
        f"reading, projection and scoring {_duration(other)}) x {remaining} frames = "
        f"{_duration(total)} of one worker"
    )
    if scheduler is not None:
        return line + "; divide by the number of dask worker threads"
    workers = resolve_jobs(jobs, remaining)
    return line + (f" / {workers} processes = {_duration(total / workers)}" if workers > 1 else "")


def _duration(seconds: float) -> str:
    """``0.8 ms``, ``1.2 s``, ``3.4 min``, ``2.1 h``."""

    def two(value: float) -> str:
        return np.format_float_positional(value, precision=2, fractional=False, trim="-")

    if seconds < 1.0:
        return f"{two(1000.0 * seconds)} ms"
    if seconds < 120.0:
        return f"{two(seconds)} s"
    if seconds < 7200.0:
        return f"{seconds / 60.0:.1f} min"
    return f"{seconds / 3600.0:.1f} h"


@dataclass
class EvaluateResult:
    """What :func:`run_evaluate` produced.

    Attributes
    ----------
    table : the paper's Table 1 layout (``table.csv``).
    caption : one line describing the table.
    out : output folder.
    frames : frames evaluated (selected and labelled, minus skipped bad frames).
    resumed : frames taken from an earlier run's parts.
    missing : frames without ``.label`` left out (``--skip-missing``).
    skipped : bad frames left out (``--skip-bad``).
    files : the tables written.
    """

    table: pd.DataFrame
    caption: str
    out: Path
    frames: int
    resumed: int
    missing: int
    skipped: list[Skipped] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)

    def text(self) -> str:
        """Caption and table (each IoU_mu and P_mu with its 95% interval), the ground
        extraction's scores, ready to print."""
        lines = [self.caption, shown_table(self.table)]
        ground = self.out / "ground.csv"
        if ground.is_file():
            lines += ground_lines(pd.read_csv(ground))
        return "\n".join(lines)


def select_labelled(
    data: Path,
    sequences: list[str] | None,
    frames: tuple[int | None, int | None] | None,
    skip_missing: bool,
) -> tuple[Dataset, list[FrameRef], int]:
    """The dataset, its selected frames that have labels, and how many lacked them.

    Raises
    ------
    FlicInputError
        Naming the missing ``.label`` files (unless ``skip_missing``), or when no frame has labels.
    """
    ds = open_dataset(data, sequences, frames, require_labels=not skip_missing)
    refs = ds.refs()
    labelled = [r for r in refs if r.label_path is not None] if ds.labelled() else []
    if not labelled:
        formats = [n for n, e in registry.FORMATS.items() if e.labelled]
        raise FlicInputError(
            data,
            "no selected frame has ground-truth labels: evaluation needs labelled data "
            f"({', '.join(formats)}; SemanticKITTI: sequences/NN/labels/*.label)",
        )
    return ds, labelled, len(refs) - len(labelled)


def run_parameters(
    data: Path,
    config: Config,
    methods: list[str],
    settings: tuple[str, ...],
    ground_remover: str,
    sequences: list[str] | None,
    frames: tuple[int | None, int | None] | None,
    command: str = "evaluate",
) -> dict[str, Any]:
    """The parameters that decide a run's results (stored in ``run.json``; JSON-normalised)."""
    effective = config.as_dict(methods)
    params = {
        "command": command,
        "data": str(Path(data).resolve()),
        "sequences": None if sequences is None else sorted(sequences),
        "frames": None if frames is None else list(frames),
        "methods": list(methods),
        "settings": list(settings),
        "ground_remover": ground_remover,
        "config": {k: effective[k] for k in ("projection", "ground", "methods")},
    }
    return json.loads(json.dumps(params, default=str))


@holding_out_lock
def run_evaluate(spec: EvaluateRun) -> EvaluateResult:
    """Evaluate methods on every selected labelled frame and write the tables to ``spec.out``.

    Parameters
    ----------
    spec : what to evaluate and how (:class:`flic_cli.runs.spec.EvaluateRun`; the selection's
        setting ``"no-ground"``, ``"ground"`` or ``"both"``, default ``"both"``; its ground
        remover defaults to ``"paper"``, the protocol's).

    Raises
    ------
    FlicInputError
        On bad input: unknown setting or method, missing labels, a bad frame (without
        ``skip_bad``) or every frame bad (with ``skip_bad``), an ``out`` folder that cannot be
        used, holds another run or is in use by a run still going (``out`` is locked for the
        run, :func:`flic_cli.io.atomic.locked_folder`).
    """
    sel = spec.selection
    config = sel.loaded_config()
    setting = sel.setting_or("both")
    ground_remover = sel.remover_or("paper")
    semantics, jobs, scheduler = spec.semantics, sel.jobs, spec.scheduler
    skip_bad, progress = sel.skip_bad, sel.progress
    # 1. what to evaluate, where to write
    if setting not in EVAL_SETTINGS:
        raise FlicInputError(None, f"--setting must be one of {', '.join(EVAL_SETTINGS)}")
    if semantics not in ("none", "oracle"):
        raise FlicInputError(None, f"--semantics must be none or oracle, got {semantics!r}")
    check_scheduler(spec.scheduler)
    bench = None if spec.runtimes is None else read_runtimes(Path(spec.runtimes))
    settings = EVAL_SETTINGS[setting]
    methods = list(dict.fromkeys(spec.methods))
    ds, refs, missing = select_labelled(sel.data, sel.sequences, sel.frames, spec.skip_missing)
    out = check_output_dir(Path(spec.out), ds.folders())
    # 2. the segmenters, built once (with the sensor's derived parameters) and sent to every
    #    worker
    config = for_dataset(config, ds, refs)
    job = ScoreJob(
        ds,
        tuple((s, tuple(build_segmenters(config, methods, s, ground_remover))) for s in settings),
        config.projection,
        oracle=semantics == "oracle",
    )
    # 3. the resumable store
    params = run_parameters(
        sel.data, config, methods, settings, ground_remover, sel.sequences, sel.frames
    )
    params["semantics"] = semantics
    kinds = ("objects", "ground") + (("panoptic",) if spec.semantics == "oracle" else ())
    done = open_store(out, params, spec.resume, kinds)
    todo = [r for r in refs if (r.sequence, r.frame) not in done]
    resumed = len(refs) - len(todo)
    if spec.on_start is not None:
        spec.on_start(len(refs), resumed, missing)
    # 4. score every frame, storing each as it finishes; the first few in this process, timed,
    #    for an estimate of the whole run before the rest starts
    parts = out / PARTS
    calibrate, rest = todo[:CALIBRATION_FRAMES], todo[CALIBRATION_FRAMES:]
    loops = [
        FrameLoop(job, calibrate, 1, None, skip_bad, "evaluate", progress, resumed, len(refs)),
        FrameLoop(
            job,
            rest,
            jobs,
            scheduler,
            skip_bad,
            "evaluate",
            progress,
            resumed + len(calibrate),
            len(refs),
        ),
    ]
    timing: list[tuple[float, FrameScores]] = []
    try:
        start = time.perf_counter()
        for ref, scores in loops[0]:
            timing.append((time.perf_counter() - start, scores))
            write_part(parts, ref.sequence, ref.frame, scores.tables())
            start = time.perf_counter()
        if timing and rest and spec.on_estimate is not None:
            spec.on_estimate(estimate_line(timing, len(rest), jobs, scheduler))
        for ref, scores in loops[1]:
            write_part(parts, ref.sequence, ref.frame, scores.tables())
    except SchedulerError:
        raise  # not a bad frame: the hint below does not apply
    except FlicInputError as exc:
        raise FlicInputError(
            exc.path,
            f"{exc.reason} (finished frames are kept in {parts} for --resume; --skip-bad goes "
            "on past bad frames)",
        ) from None
    skipped = loops[0].skipped + loops[1].skipped
    if skipped and len(skipped) == len(refs):
        write_skipped(out / "skipped.csv", sort_skipped(skipped))
        raise FlicInputError(
            sel.data,
            f"every selected frame is bad ({len(skipped)}, listed in {out / 'skipped.csv'}): "
            "nothing to evaluate",
        )
    # 5. the tables, from the stored records of the selected frames
    bad = {(s.sequence, s.frame) for s in skipped}
    keys = [(r.sequence, r.frame) for r in refs if (r.sequence, r.frame) not in bad]
    files = _write_tables(out, parts, keys, methods, settings, semantics == "oracle", bench)
    if skipped:
        files.append(write_skipped(out / "skipped.csv", sort_skipped(skipped)))
    table = pd.read_csv(out / "table.csv")
    return EvaluateResult(
        table,
        _caption(table, len(keys), settings, ground_remover),
        out,
        len(keys),
        resumed,
        missing,
        sort_skipped(skipped),
        files,
    )


def read_runtimes(path: Path) -> pd.DataFrame:
    """The ``method``, ``median_ms`` and ``frames`` of a ``flic benchmark`` ``summary.csv``."""
    path = path / "summary.csv" if path.is_dir() else path
    try:
        df = pd.read_csv(path)
    except (OSError, ValueError) as exc:
        raise FlicInputError(path, f"cannot be read as a benchmark summary ({exc})") from None
    missing = {"method", "median_ms", "frames"} - set(df.columns)
    if missing:
        raise FlicInputError(
            path, f"is not a flic benchmark summary.csv (no {', '.join(sorted(missing))})"
        )
    return df[["method", "median_ms", "frames"]]


def _write_tables(
    out: Path,
    parts: Path,
    keys: list[tuple[str, int]],
    methods: list[str],
    settings: tuple[str, ...],
    oracle: bool,
    runtimes: pd.DataFrame | None,
) -> list[Path]:
    """Read the stored records of ``keys`` and write every table atomically, and the plot."""
    seqs = sorted({k[0] for k in keys})
    objects = read_parts(
        parts, keys, "objects", OBJECT_COLUMNS, object_dtypes(methods, settings, seqs)
    )
    frames = read_parts(parts, keys, "frames", FRAME_COLUMNS, frame_dtypes(methods, settings, seqs))
    objects = objects.sort_values(
        ["method", "setting", "sequence", "frame", "instance", "class"], kind="stable"
    ).reset_index(drop=True)
    frames = frames.sort_values(["method", "setting", "sequence", "frame"], kind="stable")
    frames = frames.reset_index(drop=True)
    ground = read_parts(parts, keys, "ground", GROUND_COLUMNS, ground_dtypes(seqs))
    panoptic = None
    if oracle:
        panoptic = read_parts(
            parts, keys, "panoptic", PANOPTIC_COLUMNS, panoptic_dtypes(methods, seqs)
        )
    files = []
    tables = all_tables(objects, frames, methods, settings, panoptic, runtimes, ground)
    for name, df in tables.items():
        write_table(out / name, df)
        files.append(out / name)
    from flic_cli.plots import plot_quality_speed

    qs = tables["quality_speed.csv"]
    plot_quality_speed(
        qs["method"].tolist(),
        qs["ms_per_frame_median"].to_numpy(),
        qs["iou_mu"].to_numpy(),
        out / "quality_speed.png",
        qs["iou_mu_low"].to_numpy(),
        qs["iou_mu_high"].to_numpy(),
        title=f"IoU_mu ({qs['setting'].iloc[0]} setting, {len(keys)} frames) against time per "
        f"frame ({qs['timing'].iloc[0]})",
    )
    files.append(out / "quality_speed.png")
    return files


def _caption(table: pd.DataFrame, n_frames: int, settings: tuple[str, ...], remover: str) -> str:
    p_setting = table["p_setting"].iloc[0] if len(table) else "no-ground"
    n_objects = int(table["objects"].max()) if len(table) else 0
    remover_text = {"paper": "the paper's", "own": "each method's own"}.get(remover, remover)
    return (
        f"the paper's protocol (docs/specification.md), {n_frames} frames, "
        f"{n_objects} GT objects (>= 100 points); "
        f"IoU_mu and P_x in %, [95% bootstrap interval over frames], P_x from the {p_setting} "
        "setting"
        + (
            f"; ground setting with {remover_text} ground extraction"
            if "ground" in settings
            else ""
        )
    )

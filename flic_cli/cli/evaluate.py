"""``flic evaluate`` and ``flic sweep-threshold``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flic_cli.cli.app import (
    ConfigOpt,
    FramesOpt,
    JobsOpt,
    LabelledDataArg,
    McOpt,
    MethodOpt,
    MethodsOpt,
    SequencesOpt,
    SkipBadOpt,
    app,
    friendly_errors,
    ground_remover_option,
    selection,
)

SchedulerOpt = Annotated[
    str | None,
    typer.Option(
        "--scheduler",
        help="Address of a dask.distributed scheduler (e.g. `tcp://10.0.0.5:8786`) to send the "
        "frames to, instead of local processes. Needs `pip install 'flic[distributed]'`.",
    ),
]
SkipMissingOpt = Annotated[
    bool,
    typer.Option(
        "--skip-missing",
        help="Leave out frames without a `.label` file (and say how many) instead of failing.",
    ),
]


def _interrupted(out: Path, resumable: bool) -> None:
    hint = (
        f"; finished frames are kept in {out / 'parts'}: rerun the same command with --resume"
        if resumable
        else ""
    )
    typer.echo(f"interrupted{hint}", err=True)
    raise typer.Exit(130)


@app.command(
    epilog=(
        "Examples:\n\n"
        "- `flic evaluate` (the synthetic sample, the default methods, both settings)\n\n"
        "- `flic evaluate ~/kitti --jobs 8 --out eval/` "
        "(the paper's Table 1 on sequences 00-10)\n\n"
        "- `flic evaluate ~/kitti --sequences 08 --frames 0:500 --methods flic0,flic14 "
        "--setting no-ground`\n\n"
        "- `flic evaluate ~/kitti --out eval/ --resume` (continue an interrupted run)\n\n"
        "- `flic evaluate ~/kitti --scheduler tcp://head:8786 --out eval/` (dask cluster)\n\n"
        "Writes into OUT: `table.csv` (Table 1 layout), `per_setting.csv`, `per_sequence.csv`, "
        "`by_class.csv`, `by_distance.csv` (0-20, 20-40, >40 m), `panoptic.csv` (PQ, SQ, RQ), "
        "`quality_speed.csv` + `quality_speed.png` (IoU_mu against time per frame), "
        "`per_frame.csv` (clusters, over-/under-segmentation, time) and `per_object.csv` (one "
        "row per GT object, IoU as a fraction), `skipped.csv` with --skip-bad. Scores are in "
        "percent, intervals are 95% bootstrap intervals over frames. `parts/` holds the "
        "per-frame results as they finish and `run.json` the run's parameters."
    )
)
@friendly_errors
def evaluate(
    data: LabelledDataArg = None,
    methods: MethodsOpt = None,
    setting: Annotated[
        str,
        typer.Option(
            "--setting",
            help="`no-ground` (GT ground classes removed by label first), `ground` (each method "
            "after ground extraction) or `both` in one pass.",
        ),
    ] = "both",
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("flic-out/evaluate"),
    jobs: JobsOpt = 1,
    scheduler: SchedulerOpt = None,
    resume: Annotated[
        bool,
        typer.Option(
            "--resume",
            help="Continue the run stored in OUT (same options): frames already finished are "
            "not evaluated again.",
        ),
    ] = False,
    skip_missing: SkipMissingOpt = False,
    skip_bad: SkipBadOpt = False,
    ground_remover: Annotated[
        str,
        ground_remover_option(
            "Ground extraction of the `ground` setting (docs/specification.md: `paper`)."
        ),
    ] = "paper",
    sequences: SequencesOpt = None,
    frames: FramesOpt = None,
    config: ConfigOpt = None,
    semantics: Annotated[
        str,
        typer.Option(
            help="`none`: panoptic quality class-agnostic (thing objects) only; `oracle`: also "
            "per class with ground-truth semantics, exactly what semantic-kitti-api gives for "
            "`flic segment --semantics oracle` (one more clustering per method and frame)."
        ),
    ] = "none",
    runtimes: Annotated[
        Path | None,
        typer.Option(
            help="A `flic benchmark` output folder (or its summary.csv): quality_speed.csv "
            "takes its median times instead of this run's."
        ),
    ] = None,
) -> None:
    """Score methods with the paper's protocol (docs/specification.md): GT objects are thing
    instances with at least 100 points, each takes its best-overlap cluster (one cluster, one
    object), IoU over 3D points; IoU_mu over all objects of all frames, P_x for x = 0.50 ...
    0.95 and P_mu. Prints the paper's Table 1 and writes the tables as CSV."""
    from flic_cli.config import load_config
    from flic_cli.runs.evaluate import run_evaluate
    from flic_cli.runs.pipeline import parse_methods
    from flic_cli.runs.spec import EvaluateRun

    cfg = load_config(config)
    names = parse_methods(methods, cfg, semantics=semantics != "none")

    status: list[str] = []

    def started(total: int, done: int, missing: int) -> None:
        # said once the run succeeded: a run stopped by bad input prints its one error line only
        # (the progress bar shows the frames meanwhile)
        parts = [f"evaluated {total} frames"]
        if done:
            parts.append(f"{done} finished earlier")
        if missing:
            parts.append(f"left out {missing} frames without .label files")
        status.append(", ".join(parts))

    try:
        sel = selection(
            data, sequences, frames, setting=setting, ground_remover=ground_remover,
            config=cfg, jobs=jobs, skip_bad=skip_bad,
        )  # fmt: skip
        result = run_evaluate(
            EvaluateRun(
                sel,
                out,
                names,
                scheduler=scheduler,
                resume=resume,
                skip_missing=skip_missing,
                semantics=semantics,
                runtimes=runtimes,
                on_start=started,
                on_estimate=lambda line: typer.echo(line, err=True),
            )
        )
    except KeyboardInterrupt:
        _interrupted(out, resumable=True)
    typer.echo("\n".join(status), err=True)
    typer.echo(result.text())
    if result.skipped:
        typer.echo(
            f"skipped {len(result.skipped)} bad frame(s): "
            + "; ".join(s.line() for s in result.skipped[:3])
            + (" ..." if len(result.skipped) > 3 else ""),
            err=True,
        )
    typer.echo(f"wrote {', '.join(p.name for p in result.files)} -> {result.out}")


@app.command(
    name="sweep-threshold",
    epilog=(
        "Examples:\n\n"
        "- `flic sweep-threshold` (FLIC's distance threshold on the synthetic sample)\n\n"
        "- `flic sweep-threshold ~/kitti --sequences 08 --method flic --mc 0 --from 0.2 --to 1.5 "
        "--step 0.05 --jobs 8` (paper Fig. 8)\n\n"
        "- `flic sweep-threshold ~/kitti --method bogoslavskyi --from 2 --to 30 --step 1`\n\n"
        "- `flic sweep-threshold ~/kitti --method dbscan --setting ground`\n\n"
        "Defaults of --from/--to/--step: flic 0.2..1.5 step 0.05 m, bogoslavskyi 2..30 step 1 "
        "deg, dbscan 0.2..1.5 step 0.1 m. Writes `sweep.csv` (one row per value, scores in "
        "percent) and `sweep.png` (the curve, best value dashed)."
    ),
)
@friendly_errors
def sweep_threshold(
    data: LabelledDataArg = None,
    method: MethodOpt = "flic",
    mc: McOpt = None,
    start: Annotated[
        float | None,
        typer.Option("--from", help="First value (FLIC/DBSCAN metres, Bogoslavskyi degrees)."),
    ] = None,
    stop: Annotated[float | None, typer.Option("--to", help="Last value (included).")] = None,
    step: Annotated[float | None, typer.Option("--step", help="Step between values.")] = None,
    setting: Annotated[
        str,
        typer.Option(
            "--setting",
            help="`no-ground` (GT ground removed by label: isolates the clusterer) or `ground`.",
        ),
    ] = "no-ground",
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("flic-out/sweep"),
    jobs: JobsOpt = 1,
    scheduler: SchedulerOpt = None,
    skip_missing: SkipMissingOpt = False,
    skip_bad: SkipBadOpt = False,
    ground_remover: Annotated[
        str, ground_remover_option("Ground extraction of the `ground` setting.")
    ] = "paper",
    sequences: SequencesOpt = None,
    frames: FramesOpt = None,
    config: ConfigOpt = None,
) -> None:
    """IoU_mu and P_mu against a method's main parameter (FLIC's distance threshold,
    Bogoslavskyi's angle, DBSCAN's eps), like the paper's Fig. 8. Each frame is read and
    projected once for all values."""
    from flic_cli.config import load_config
    from flic_cli.runs.pipeline import resolve_method
    from flic_cli.runs.spec import SweepRun
    from flic_cli.runs.sweep import run_sweep

    cfg = load_config(config)
    try:
        sel = selection(
            data, sequences, frames, setting=setting, ground_remover=ground_remover,
            config=cfg, jobs=jobs, skip_bad=skip_bad,
        )  # fmt: skip
        result = run_sweep(
            SweepRun(
                sel,
                out,
                resolve_method(method, mc),
                start,
                stop,
                step,
                scheduler=scheduler,
                skip_missing=skip_missing,
            )
        )
    except KeyboardInterrupt:
        _interrupted(out, resumable=False)
    if result.missing:
        typer.echo(f"left out {result.missing} frames without .label files", err=True)
    if result.skipped:
        typer.echo(f"skipped {len(result.skipped)} bad frame(s), listed in skipped.csv", err=True)
    typer.echo(result.table.to_string(index=False, na_rep="-", float_format=lambda v: f"{v:.2f}"))
    typer.echo(result.line())

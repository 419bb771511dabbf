"""``flic benchmark``: per-frame runtime of the methods (paper section IV-A, Fig. 9 and 10)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flic_cli.cli.app import (
    CalibrationOpt,
    ColumnsOpt,
    ConfigOpt,
    DataArg,
    FramesOpt,
    MethodsOpt,
    ReturnOpt,
    RowsOpt,
    SequencesOpt,
    SettingOpt,
    SkipBadOpt,
    TopicOpt,
    app,
    friendly_errors,
    ground_remover_option,
    reader_options,
    selection,
)


@app.command(
    epilog=(
        "Examples:\n\n"
        "- `flic benchmark` (the synthetic sample's Moosmann-style log, the default methods)\n\n"
        "- `flic benchmark ~/moosmann/log1 --out bench/ --slow-every 25`\n\n"
        "- `flic benchmark ~/kitti --sequences 08 --frames 0:500 --methods flic0,flic14 "
        "--repeat 3`"
    )
)
@friendly_errors
def benchmark(
    data: DataArg = None,
    methods: MethodsOpt = None,
    out: Annotated[
        Path,
        typer.Option(help="Output folder for the CSV tables, environment.json and the plots."),
    ] = Path("flic-out/benchmark"),
    sequences: SequencesOpt = None,
    frames: FramesOpt = None,
    setting: SettingOpt = "ground",
    config: ConfigOpt = None,
    ground_remover: Annotated[
        str,
        ground_remover_option(
            "Ground extraction of the `ground` setting, timed as part of every method."
        ),
    ] = "own",
    warmup: Annotated[
        int,
        typer.Option(
            min=0,
            help="Untimed runs of every method on the first frame (excludes JIT compilation).",
        ),
    ] = 3,
    repeat: Annotated[
        int,
        typer.Option(
            min=1, help="Timed runs per frame and method, back to back; the median is kept."
        ),
    ] = 1,
    rounds: Annotated[
        int,
        typer.Option(
            min=1,
            help="Rounds of passes over the selection (one pass per method, the order turned "
            "each round); each frame's median over the rounds is kept (disturbances by other "
            "work on a shared machine do not meet every round).",
        ),
    ] = 1,
    slow_every: Annotated[
        int,
        typer.Option(
            "--slow-every",
            "--dbscan-every",
            min=1,
            help="Time the methods declared slow (DBSCAN: seconds per frame) on every N-th frame "
            "only. `--dbscan-every` is the same option.",
        ),
    ] = 10,
    threads: Annotated[
        int,
        typer.Option(min=1, help="Threads of numba and the BLAS/OpenMP pools while timing."),
    ] = 1,
    plots: Annotated[
        bool, typer.Option("--plots/--no-plots", help="Write runtime.png, boxplot_hz.png, ...")
    ] = True,
    skip_bad: SkipBadOpt = False,
    topic: TopicOpt = None,
    columns: ColumnsOpt = None,
    rows: RowsOpt = None,
    return_index: ReturnOpt = None,
    calibration: CalibrationOpt = None,
) -> None:
    """Time the segmentation of every frame (range image in, labels out, ground extraction
    included), single-threaded, after a warm-up, each method in a pass over the frames of its
    own (as in a pipeline: the frame read, then the method); file reading and projection are
    timed as separate stages. Writes `frames.csv`, `summary.csv` (median/mean/p5/p95/p99/max
    in ms, Hz, p99/median stability, speed-ups), `histogram.csv`, `environment.json` and the
    plots of the paper's Fig. 9 and 10 into OUT."""
    # Before numpy/numba are imported: their thread pools read these variables once.
    from flic_cli.runs.environment import pin_thread_env

    pin_thread_env(threads)

    from flic_cli.config import load_config
    from flic_cli.runs.benchmark import run_benchmark
    from flic_cli.runs.pipeline import parse_methods
    from flic_cli.runs.spec import BenchmarkRun

    cfg = load_config(config)
    names = parse_methods(methods, cfg)
    sel = selection(
        data, sequences, frames, topic, moosmann=True, setting=setting,
        ground_remover=ground_remover, config=cfg, skip_bad=skip_bad,
        reader=reader_options(columns, rows, return_index, calibration),
    )  # fmt: skip
    result = run_benchmark(
        BenchmarkRun(sel, out, names, warmup, repeat, rounds, slow_every, threads, plots)
    )
    typer.echo(result.report())

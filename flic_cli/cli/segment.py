"""``flic segment``, ``flic sample`` and ``flic config``."""

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
    JobsOpt,
    McOpt,
    MethodOpt,
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
        "- `flic segment` (the synthetic sample, FLIC without MC)\n\n"
        "- `flic segment ~/kitti --sequences 08 --frames 0:500 --method flic --mc 14 "
        "--out pred/`\n\n"
        "- `flic segment ~/moosmann/log1 --method bogoslavskyi --render 10 --out pred/`\n\n"
        "- `flic segment ~/kitti --sequences 08 --method flic14 --semantics oracle --out pan/` "
        "(panoptic predictions for semantic-kitti-api)\n\n"
        "- `flic segment ~/kitti --frames 0:10 --export ply --out ply/`\n\n"
        "- `flic segment drive.bag --topic /velodyne_points --export mcap --out seg/` (a ROS 2 "
        "bag of clusters for Foxglove / RViz)\n\n"
        "A run that stops at a bad frame writes nothing (use --skip-bad to go on past it)."
    )
)
@friendly_errors
def segment(
    data: DataArg = None,
    method: MethodOpt = "flic",
    mc: McOpt = None,
    out: Annotated[Path, typer.Option(help="Output root for sequences/NN/predictions/.")] = Path(
        "flic-out/segment"
    ),
    sequences: SequencesOpt = None,
    frames: FramesOpt = None,
    setting: SettingOpt = "ground",
    config: ConfigOpt = None,
    ground_remover: Annotated[
        str, ground_remover_option("Ground extraction of the `ground` setting.")
    ] = "own",
    render: Annotated[
        int | None,
        typer.Option(
            help="Also draw this frame number (one of the selected frames): its range image "
            "(render_*.png) and bird's-eye and 3D views (views_*.png), with labels ground truth "
            "beside the prediction and missed, split and merged objects marked."
        ),
    ] = None,
    semantics: Annotated[
        str,
        typer.Option(
            help="Semantic classes written with the clusters (SemanticKITTI): `none` (class 0); "
            "`oracle` (each point's ground-truth class, an upper bound); or DIR, a semantic "
            "network's predictions (DIR/sequences/NN/predictions/NNNNNN.label). With semantics "
            "only the points of thing classes are clustered, without ground extraction."
        ),
    ] = "none",
    export: Annotated[
        list[str] | None,
        typer.Option(
            help="Also write each frame as: `ply` (a PLY point cloud with cluster ids and colours, "
            "for CloudCompare, MeshLab, Open3D); for a bag input `mcap` or `bag` (a ROS 2 bag, "
            "MCAP or sqlite3, of sensor_msgs/PointCloud2 x y z intensity cluster on "
            "/flic/clusters with the input's stamps and frame id, for RViz / Foxglove). "
            "Repeatable."
        ),
    ] = None,
    jobs: JobsOpt = 1,
    skip_bad: SkipBadOpt = False,
    topic: TopicOpt = None,
    columns: ColumnsOpt = None,
    rows: RowsOpt = None,
    return_index: ReturnOpt = None,
    calibration: CalibrationOpt = None,
) -> None:
    """Segment scans and write predictions: for SemanticKITTI `.label` files (cluster id in the
    upper 16 bits, 0 = unclustered, the semantic class in the lower 16; one label per point of
    the `.bin`) under `OUT/sequences/NN/predictions/`, for Moosmann logs 16-bit label images
    `OUT/<log>/scanNNNNN.label.png` (the cluster id of each pixel, 0 = none)."""
    from flic_cli.config import load_config
    from flic_cli.runs.pipeline import resolve_method
    from flic_cli.runs.segment import run_segment
    from flic_cli.runs.spec import SegmentRun

    sel = selection(
        data, sequences, frames, topic, setting=setting, ground_remover=ground_remover,
        config=load_config(config), jobs=jobs, skip_bad=skip_bad,
        reader=reader_options(columns, rows, return_index, calibration),
    )  # fmt: skip
    summary = run_segment(
        SegmentRun(sel, out, resolve_method(method, mc), render, semantics, tuple(export or ()))
    )
    typer.echo(summary.line())


@app.command(
    epilog="Examples: `flic sample /tmp/flic-sample --frames 50`, "
    "`flic sample /tmp/vlp16 --sensor vlp16 --frames 10`"
)
@friendly_errors
def sample(
    out: Annotated[Path, typer.Argument(help="Output folder.")],
    frames: Annotated[int, typer.Option("--frames", help="Number of frames (>= 1).")] = 20,
    seed: Annotated[int, typer.Option(help="Scene seed.")] = 0,
    sensor: Annotated[
        str,
        typer.Option(
            help="Sensor profile: vlp16, vlp32c, hdl32e, hdl64e (the default), os1-64, os1-128, "
            "os2-128. Other than hdl64e: the SemanticKITTI sequence only, cast with that "
            "sensor's beam table and columns, and OUT/sensor.toml, the `--config` that reads it."
        ),
    ] = "hdl64e",
) -> None:
    """Write the deterministic synthetic sample: a SemanticKITTI sequence (with labels) and the
    same scenes as a Moosmann-style log (16-bit PNG + img.cfg)."""
    from flic_cli.sample import write_sample

    paths = write_sample(out, frames=frames, seed=seed, sensor=sensor)
    if paths.config is None:
        typer.echo(f"wrote {frames} frames: {paths.kitti_root} and {paths.moosmann_log}")
    else:
        typer.echo(
            f"wrote {frames} frames ({sensor}): {paths.kitti_root}; read it with "
            f"--config {paths.config}"
        )


@app.command(
    name="config",
    epilog=(
        "Examples:\n\n"
        "- `flic config` (the presets, every default included)\n\n"
        "- `flic config --config my.toml` (what a run with `--config my.toml` uses)"
    ),
)
@friendly_errors
def show_config(config: ConfigOpt = None) -> None:
    """Print the effective configuration as TOML: the presets with your `--config` laid over
    them, every parameter of every component with its value (defaults included). Errors in your
    file are reported with the file, the table and key, and the reason."""
    import tomli_w

    from flic_cli.config import load_config

    cfg = load_config(config)
    typer.echo(tomli_w.dumps(cfg.as_dict(), multiline_strings=False), nl=False)

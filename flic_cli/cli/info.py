"""``flic info``: what a dataset or recording holds, as flic reads it."""

from __future__ import annotations

from typing import Annotated, Any

import typer

from flic_cli.cli.app import (
    CalibrationOpt,
    ColumnsOpt,
    DataArg,
    FramesOpt,
    ReturnOpt,
    RowsOpt,
    SequencesOpt,
    TopicOpt,
    _selection,
    app,
    friendly_errors,
    reader_options,
)


@app.command(
    epilog=(
        "Examples:\n\n"
        "- `flic info recording.pcap` (an Ouster pcap with its JSON beside it, or Velodyne)\n\n"
        "- `flic info cloud.pcd`, `flic info nuscenes/samples/LIDAR_TOP/`, `flic info ~/kitti "
        "--sequences 08 --frames 0:100`\n\n"
        "- `flic info drive.bag` (a bag or MCAP file: its topics, types and message counts, then "
        "the LiDAR topic as below; `--topic` picks one)\n\n"
        "Prints per recording (sequence): the format, the sensor, the frames (revolutions), beams "
        "x columns, points per frame, the projection coverage (share of the points that own a "
        "pixel of the range image) and where the beam angles came from."
    )
)
@friendly_errors
def info(
    data: DataArg = None,
    sequences: SequencesOpt = None,
    frames: FramesOpt = None,
    sample: Annotated[
        int,
        typer.Option(
            "--sample",
            min=1,
            help="Frames per recording read for the points and coverage figures (evenly spread).",
        ),
    ] = 20,
    topic: TopicOpt = None,
    columns: ColumnsOpt = None,
    rows: RowsOpt = None,
    return_index: ReturnOpt = None,
    calibration: CalibrationOpt = None,
) -> None:
    """Show the format, sensor, frames, image size, points and coverage of DATA."""
    from flic_cli.cli.app import _data_or_sample
    from flic_cli.io.bag import info_lines, is_bag

    path = _data_or_sample(data)
    seqs, frame_range = _selection(sequences, frames, topic)
    if is_bag(path):  # the bag's topics first, then its LiDAR topic like any recording
        lines, chosen = info_lines(path, seqs[0] if seqs else None)
        for line in lines:
            typer.echo(line)
        if not chosen:
            return
    reader = reader_options(columns, rows, return_index, calibration)
    for line in describe(path, seqs, frame_range, sample, reader):
        typer.echo(line)


def describe(
    path: Any, sequences: Any, frames: Any, sample: int = 20, reader: Any = None
) -> list[str]:
    """The lines ``flic info`` prints."""
    import numpy as np

    from flic_cli import registry
    from flic_cli.io import open_dataset
    from flic_cli.projection import Projection

    ds = open_dataset(path, sequences, frames, reader=reader)
    entry = registry.FORMATS.get(ds.format)
    lines = [f"data: {path}", f"format: {ds.format}" + (f" ({entry.summary})" if entry else "")]
    by_seq: dict[str, list] = {}
    for ref in ds.refs():
        by_seq.setdefault(ref.sequence, []).append(ref)
    projection = Projection()
    for seq, refs in by_seq.items():
        lines.append(f"recording {seq}: {refs[0].path if len(by_seq) > 1 else ''}".rstrip())
        file_info = getattr(ds, "infos", {}).get(seq)
        picked = [refs[i] for i in np.unique(np.linspace(0, len(refs) - 1, sample).astype(int))]
        points, owned, valid, shapes, projections = [], [], [], set(), set()
        for ref in picked:
            frame = ds.load(ref)
            image = frame.image if frame.image is not None else projection(frame.points)
            points.append(frame.points.shape[0])
            owned.append(int(np.count_nonzero(image.ranges)))
            valid.append(frame.n_read)
            shapes.add(image.shape)
            projections.add(image.projection)
        n_partial = len(file_info.partial) if file_info is not None else 0
        text = f"{len(refs)}" + (
            " revolution(s)" if registry.FORMATS[ds.format].frames_per_file == "many" else ""
        )
        if n_partial:
            text += f"; left out (incomplete): {'; '.join(file_info.partial)}"
        model = ds.sensor(refs[0]) if hasattr(ds, "sensor") else None
        if model is not None:
            desc = model.describe()
            lines.append(f"  sensor: {desc.pop('sensor')}")
            lines.append(f"  frames: {text}")
            lines.append(f"  beams x columns: {desc.pop('beams x columns')}")
        else:
            lines.append(f"  frames: {text}")
            hw = ", ".join(f"{h} x {w}" for h, w in sorted(shapes))
            lines.append(f"  beams x columns: {hw} ({', '.join(sorted(projections))} projection)")
        stored = "" if points == valid else f" (of {min(valid):,}..{max(valid):,} stored)"
        lines.append(f"  points per frame: {_span(points)}{stored} over {len(picked)} frame(s)")
        cover = np.array(owned) / np.maximum(np.array(points), 1)
        lines.append(
            f"  projection coverage: {100 * cover.min():.1f} .. {100 * cover.max():.1f} % of the "
            f"points own a pixel (valid pixels {_span(owned)})"
        )
        if model is not None:
            for key, value in desc.items():
                lines.append(f"  {key}: {value}")
        elif registry.FORMATS[ds.format].beam_angles is not None:
            lines.append(f"  beam angles from: {registry.FORMATS[ds.format].beam_angles}")
        else:
            how = "ring recovery from the scan order" if "rings" in projections else "spherical"
            lines.append(f"  beam angles from: estimated ({how}; [projection] of the config)")
        from flic_cli.config import load_config
        from flic_cli.sensor_params import BeamTable, derived_lines

        lines += [f"  {line}" for line in derived_lines(BeamTable.of_image(image), load_config())]
    return lines


def _span(values: list[int]) -> str:
    lo, hi = min(values), max(values)
    return f"{lo:,}" if lo == hi else f"{lo:,} .. {hi:,}"

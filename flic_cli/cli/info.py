"""``flic info``: what a DATA path holds (for bags: topics, types and message counts)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flic_cli.cli.app import TopicOpt, app, friendly_errors


@app.command(
    epilog=(
        "Examples:\n\n"
        "- `flic info drive.bag` (topics, types, message counts; the LiDAR topic's sensor)\n\n"
        "- `flic info drive.mcap --topic /ouster/points`"
    )
)
@friendly_errors
def info(
    data: Annotated[Path, typer.Argument(help="A bag, MCAP file or dataset.")],
    topic: TopicOpt = None,
) -> None:
    """Describe DATA: for a bag or MCAP file every topic with its message type and count, and
    the LiDAR topic's revolutions, beams x columns and where the beam angles came from; for a
    dataset its format and frames."""
    from flic_cli.errors import FlicInputError
    from flic_cli.io import open_dataset
    from flic_cli.io.bag import info_lines, is_bag

    if not data.exists():
        raise FlicInputError(data, "does not exist")
    if is_bag(data):
        for line in info_lines(data, topic):
            typer.echo(line)
        return
    ds = open_dataset(data)
    typer.echo(f"format: {ds.format}")
    typer.echo(f"frames: {len(ds.refs())}")

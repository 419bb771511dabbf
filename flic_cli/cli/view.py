"""``flic view``: the clusters in an interactive 3D window, or a screenshot of them."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flic_cli.cli.app import (
    ConfigOpt,
    DataArg,
    FramesOpt,
    SequencesOpt,
    TopicOpt,
    _data_or_sample,
    _selection,
    app,
    friendly_errors,
    ground_remover_option,
)


@app.command(
    epilog=(
        "Examples:\n\n"
        "- `flic view` (the synthetic sample: ground truth beside FLIC's clusters)\n\n"
        "- `flic view drive.bag --method flic14,bogoslavskyi --frames 0:100`\n\n"
        "- `flic view ~/kitti --sequences 08 --frames 0 --screenshot shot.png` (no window)"
    )
)
@friendly_errors
def view(
    data: DataArg = None,
    method: Annotated[
        str,
        typer.Option(
            help="Method variant(s), comma-separated: the first is shown, the window's menu "
            "switches between them. Default: flic14 and the config's default methods."
        ),
    ] = "",
    frames: FramesOpt = None,
    sequences: SequencesOpt = None,
    topic: TopicOpt = None,
    config: ConfigOpt = None,
    ground_remover: Annotated[
        str, ground_remover_option("Ground extraction before the clustering.")
    ] = "own",
    screenshot: Annotated[
        Path | None,
        typer.Option(
            help="Render the first selected frame from above into this PNG without opening a "
            "window (EGL; works without a display) and exit."
        ),
    ] = None,
) -> None:
    """Look at the clusters in 3D (polyscope, `pip install 'flic[viewer]'`): points coloured
    by cluster, the ground light grey, unclustered points dark grey; with labels the ground
    truth beside the prediction (an object in the colour of the cluster that found it). The
    window steps through the frames and switches between methods."""
    from flic_cli.config import load_config
    from flic_cli.runs.pipeline import parse_methods
    from flic_cli.viewer import Viewer, polyscope

    polyscope()  # the install hint before any work
    cfg = load_config(config)
    names = parse_methods(method or None, cfg) if method else ["flic14", *cfg.default_methods]
    names = list(dict.fromkeys(names))
    seqs, frm = _selection(sequences, frames, topic)
    viewer = Viewer(_data_or_sample(data), names, frm, seqs, cfg, ground_remover)
    viewer.init(headless=screenshot is not None)
    if screenshot is not None:
        vf = viewer.screenshot(screenshot)
        typer.echo(f"{vf.title} -> {screenshot}")
        return
    viewer.show()

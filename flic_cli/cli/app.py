"""The Typer app and what every command shares: option names, error handling, data selection.

Heavy modules are imported inside the commands, so ``flic --help`` answers at once."""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer

app = typer.Typer(
    name="flic",
    help=(
        "FLIC (Fast Lidar Image Clustering) and its peers -- Bogoslavskyi & Stachniss, DBSCAN -- "
        "on SemanticKITTI sequences and Moosmann-style logs: segment, evaluate, benchmark.\n\n"
        "Without a DATA path every command runs on a synthetic sample that flic makes itself."
    ),
    no_args_is_help=True,
    rich_markup_mode="markdown",
    pretty_exceptions_enable=False,
    add_completion=False,
)

# ---- options shared by every command (same names everywhere) -------------------------------
DataArg = Annotated[
    Path | None,
    typer.Argument(
        help="SemanticKITTI root (with sequences/), one sequence folder, or a Moosmann log "
        "(img.cfg + scanNNNNN.png). Default: the built-in synthetic sample.",
        show_default=False,
    ),
]
SequencesOpt = Annotated[
    str | None, typer.Option("--sequences", help="Comma-separated sequences, e.g. `00,05`.")
]
FramesOpt = Annotated[
    str | None,
    typer.Option("--frames", help="Frame range START:STOP (stop excluded), e.g. `0:100`, `500:`."),
]
SettingOpt = Annotated[
    str,
    typer.Option(
        "--setting",
        help="`ground`: each method runs after ground extraction (no labels used); "
        "`no-ground`: the ground classes' points are removed by label first.",
    ),
]
ConfigOpt = Annotated[
    Path | None,
    typer.Option("--config", help="TOML file overriding configs/default.toml (same layout)."),
]


MethodOpt = Annotated[
    str,
    typer.Option(help="`flic`, `bogoslavskyi`, `dbscan` or any [methods.NAME] of the config."),
]
McOpt = Annotated[
    int | None, typer.Option(help="Map Connections for `--method flic`: 0, 1, 6 or 14.")
]
OwnGroundOpt = Annotated[
    str,
    typer.Option(
        "--ground-remover",
        help="`own` (each method's own, e.g. Bogoslavskyi's for bogoslavskyi), `paper` or "
        "`bogoslavskyi`.",
    ),
]


def _fail(message: str) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(2)


def friendly_errors(func: Callable[..., Any]) -> Callable[..., Any]:
    """Turn bad input into one line on stderr and exit code 2 (no traceback)."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        from flic_cli.errors import FlicInputError

        warnings.simplefilter("default")
        warnings.formatwarning = lambda msg, cat, *a, **k: f"warning: {msg}\n"
        try:
            return func(*args, **kwargs)
        except FlicInputError as exc:
            _fail(str(exc))
        except KeyboardInterrupt:
            typer.echo("interrupted", err=True)
            raise typer.Exit(130) from None

    return wrapper


def _data_or_sample(data: Path | None, moosmann: bool = False) -> Path:
    if data is not None:
        return data
    from flic_cli.sample import ensure_sample

    paths = ensure_sample()
    chosen = paths.moosmann_log if moosmann else paths.kitti_root
    typer.echo(f"no DATA given: using the built-in synthetic sample {chosen}", err=True)
    return chosen


def _selection(sequences: str | None, frames: str | None) -> tuple[Any, Any]:
    from flic_cli.io import parse_frames, parse_sequences

    return (
        parse_sequences(sequences) if sequences else None,
        parse_frames(frames) if frames else None,
    )

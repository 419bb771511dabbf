"""The Typer app and what every command shares: option names, error handling, data selection.

Heavy modules are imported inside the commands, so ``flic --help`` answers at once. Option help
that lists formats or ground removers is built from :mod:`flic_cli.registry`, the one place they
are named.
"""

from __future__ import annotations

import errno
import functools
import os
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer
import typer.core

from flic_cli import registry

app = typer.Typer(
    name="flic",
    help=(
        "FLIC (Fast Lidar Image Clustering), Bridge and the field's clusterers -- Bogoslavskyi & "
        "Stachniss, DBSCAN, Euclidean, SLR, CVC, ALPINE, HDBSCAN -- on SemanticKITTI sequences, "
        "Moosmann-style logs, sensor recordings (Ouster, Velodyne, PCD, nuScenes) and ROS bags: "
        "segment, evaluate, benchmark, sweep-threshold.\n\n"
        "Without a DATA path every command runs on a synthetic sample that flic makes itself."
    ),
    no_args_is_help=True,
    rich_markup_mode="markdown",
    pretty_exceptions_enable=False,
    add_completion=False,
)


def _no_type_for_flags(display: Callable[..., Any]) -> Callable[..., Any]:
    """Typer's rich help shows a ``<bool>`` type beside every on/off flag; flags take no value,
    so they get no type column."""

    @functools.wraps(display)
    def wrapper(self: Any, ctx: Any) -> Any:
        return None if getattr(self, "is_flag", False) else display(self, ctx)

    return wrapper


if hasattr(typer.core, "TyperOption") and hasattr(typer.core.TyperOption, "display_type_rich"):
    typer.core.TyperOption.display_type_rich = _no_type_for_flags(
        typer.core.TyperOption.display_type_rich
    )

_SAMPLE = "Default: the built-in synthetic sample."

# ---- options shared by every command (same names everywhere) -------------------------------
DataArg = Annotated[
    Path | None,
    typer.Argument(
        help=f"The data: {registry.choices(registry.FORMATS)}. {_SAMPLE}", show_default=False
    ),
]
LabelledDataArg = Annotated[
    Path | None,
    typer.Argument(
        help=f"Labelled data: {registry.choices(registry.FORMATS, labelled_only=True)}. {_SAMPLE}",
        show_default=False,
    ),
]
SequencesOpt = Annotated[
    str | None,
    typer.Option(
        "--sequences",
        help="Comma-separated sequences (or log folders), e.g. `00,05`. Default: all.",
    ),
]
FramesOpt = Annotated[
    str | None,
    typer.Option(
        "--frames",
        help="Frame numbers START:STOP (stop excluded), e.g. `0:100`, `500:`, `7`. Default: all.",
    ),
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
    typer.Option(
        "--config",
        help="TOML file laid over the presets (configs/default.toml): only the keys it changes, "
        "and new method variants. `flic config` prints the result.",
    ),
]
MethodOpt = Annotated[
    str,
    typer.Option(
        help="A method variant of the config: `flic`, `bogoslavskyi`, `dbscan` or any "
        "[methods.NAME] (`flic config` lists them)."
    ),
]
MethodsOpt = Annotated[
    str | None,
    typer.Option(
        "--methods",
        "-m",
        help="Comma-separated method variants, in table order. Default: the config's "
        "`default_methods` (`flic config` shows them).",
        show_default=False,
    ),
]
McOpt = Annotated[
    int | None,
    typer.Option(
        help="Map Connections for `--method flic`: 0, 1, 6 or 14 (the presets flic0 ... flic14). "
        "Left out, `--method flic` means 0 MC."
    ),
]
JobsOpt = Annotated[
    int,
    typer.Option(
        "--jobs",
        "-j",
        help="Processes on this machine, one frame each at a time; 0 or a negative number: one "
        "per CPU core. Results do not depend on it.",
    ),
]
SkipBadOpt = Annotated[
    bool,
    typer.Option(
        "--skip-bad",
        help="Go on past frames whose input is bad (say which, and list them in skipped.csv) "
        "instead of stopping at the first with an error naming its file.",
    ),
]

TopicOpt = Annotated[
    str | None,
    typer.Option(
        "--topic",
        help="Bags and MCAP files: the LiDAR topic to read (PointCloud2, VelodyneScan or Ouster "
        "packets). Default: the bag's only LiDAR topic.",
    ),
]

ColumnsOpt = Annotated[
    int | None,
    typer.Option(
        "--columns",
        help="PCD: columns per revolution W (the firings of a turn, e.g. 1800 for 0.2 deg). "
        "Default: estimated from the median azimuth step between a ring's points.",
    ),
]
CalibrationOpt = Annotated[
    Path | None,
    typer.Option(
        "--calibration",
        help="Velodyne pcap: a velodyne-decoder calibration (YAML) instead of the model's "
        "built-in one; an HDL-64E whose packets carry none needs it.",
    ),
]
ReturnOpt = Annotated[
    int | None,
    typer.Option(
        "--return",
        help="Ouster pcap of a dual-return profile: the return each pixel is read from, 1 "
        "(the first, default) or 2.",
    ),
]
RowsOpt = Annotated[
    int | None,
    typer.Option(
        "--rows",
        help="PCD without a ring field: the sensor's beams (rows). Default: estimated from "
        "gaps in the points' elevations.",
    ),
]


def ground_remover_option(default_help: str) -> Any:
    """The ``--ground-remover`` option, listing the registered removers."""
    return typer.Option(
        "--ground-remover",
        help=f"{default_help} Removers: {registry.choices(registry.REMOVERS)}; `own`: each "
        "method variant's own (its `ground` key, e.g. Bogoslavskyi's for bogoslavskyi).",
    )


def _fail(message: str) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(2)


def friendly_errors(func: Callable[..., Any]) -> Callable[..., Any]:
    """Bad input becomes one line on stderr and exit code 2 (no traceback); warnings print as
    ``warning: <file>: <message>``."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        from flic_cli.errors import FlicInputError, show_warning

        warnings.simplefilter("default")
        warnings.showwarning = show_warning
        try:
            return func(*args, **kwargs)
        except FlicInputError as exc:
            _fail(str(exc))
        except OSError as exc:  # a disk that fills up under a write no check could foresee
            if exc.errno not in (errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)):
                raise
            _fail(f"{exc.filename or 'output'}: cannot be written: {os.strerror(exc.errno)}")
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


def _selection(
    sequences: str | None, frames: str | None, topic: str | None = None
) -> tuple[Any, Any]:
    """The parsed ``--sequences`` (a bag's ``--topic`` takes their place) and ``--frames``."""
    from flic_cli.io import parse_frames, parse_sequences

    seqs = parse_sequences(sequences) if sequences else None
    return [topic] if topic else seqs, parse_frames(frames) if frames else None


def reader_options(
    columns: int | None, rows: int | None, return_index: int | None, calibration: Path | None
) -> dict[str, Any]:
    """The reader options (``--columns``, ``--rows``, ``--return``, ``--calibration``) as
    :func:`flic_cli.io.open_dataset` takes them."""
    return {"columns": columns, "rows": rows, "return": return_index, "calibration": calibration}


def selection(
    data: Path | None,
    sequences: str | None,
    frames: str | None,
    topic: str | None = None,
    *,
    moosmann: bool = False,
    **options: Any,
) -> Any:
    """The :class:`flic_cli.runs.spec.Selection` of a command's shared options: DATA (or the
    sample: its Moosmann log when ``moosmann``), ``--sequences`` / ``--topic``, ``--frames``,
    and ``options`` (``setting``, ``ground_remover``, ``config``, ``jobs``, ``skip_bad``)."""
    from flic_cli.runs.spec import Selection

    seqs, frm = _selection(sequences, frames, topic)
    return Selection(_data_or_sample(data, moosmann), seqs, frm, **options)

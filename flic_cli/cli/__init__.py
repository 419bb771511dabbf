"""The ``flic`` command line: one module per command group, all registered on one Typer app.

To add a command: a module here that decorates its function with ``@app.command()`` (import heavy
modules inside the function), imported below. :func:`main` is the installed ``flic`` program.
"""

from __future__ import annotations

import sys

import typer

from flic_cli.cli import (  # noqa: F401  (registers the commands)
    benchmark,
    evaluate,
    info,
    segment,
    view,
)
from flic_cli.cli.app import app

__all__ = ["app", "main"]


def main(argv: list[str] | None = None) -> None:
    """Run ``flic``: like ``app()``, but a mistyped command line also gets a one-line error.

    Click reports usage errors (an unknown option, ``--jobs abc``, a value below an option's
    minimum) in a multi-line box; here they become ``error: <what is wrong> (see flic CMD
    --help)`` and exit code 2, like every other bad input.
    """
    from flic_cli.runs.environment import keep_freed_memory

    keep_freed_memory()  # every frame reuses the same buffers (see its docstring)
    _terminate_like_ctrl_c()
    command = typer.main.get_command(app)
    click = _click_exceptions(command)
    ClickException = click.ClickException  # noqa: N806
    NoArgsIsHelpError = getattr(click, "NoArgsIsHelpError", ())  # noqa: N806
    try:
        code = command.main(args=argv, prog_name="flic", standalone_mode=False)
    except NoArgsIsHelpError as exc:
        typer.echo(exc.ctx.get_help() if exc.ctx is not None else exc.format_message())
        sys.exit(2)
    except ClickException as exc:
        ctx = getattr(exc, "ctx", None)
        hint = f" (see {ctx.command_path} --help)" if ctx is not None else ""
        typer.echo(f"error: {exc.format_message()}{hint}", err=True)
        sys.exit(exc.exit_code)
    sys.exit(code if isinstance(code, int) else 0)


def _click_exceptions(command: object) -> object:
    """The ``exceptions`` module of the click that built ``command`` (typer vendors its own copy
    of click in recent versions and uses the ``click`` package in older ones)."""
    import importlib

    for cls in type(command).__mro__:
        module = cls.__module__
        if module.endswith(".core") and module != "typer.core":
            return importlib.import_module(module.removesuffix(".core") + ".exceptions")
    return importlib.import_module("click.exceptions")  # pragma: no cover


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled like Ctrl-C: ``finally`` blocks run, so staging folders and temporary
    files are removed and finished work is kept, then flic exits (code 130)."""


def _raise_terminated(signum: int, frame: object) -> None:
    raise Terminated()


def _terminate_like_ctrl_c() -> None:
    """Make SIGTERM (``kill``, a job scheduler's stop) clean up as Ctrl-C does, unless the
    caller already chose what SIGTERM does."""
    import signal

    if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _raise_terminated)

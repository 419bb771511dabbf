"""The ``flic`` command line: one module per command group, all registered on one Typer app.

To add a command: a module here that decorates its function with ``@app.command()`` (import heavy
modules inside the function), imported below.
"""

from flic_cli.cli import benchmark, evaluate, segment  # noqa: F401  (registers the commands)
from flic_cli.cli.app import app

__all__ = ["app"]

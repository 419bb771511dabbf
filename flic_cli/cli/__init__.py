"""The ``flic`` command line: one module per command group, all registered on one Typer app.

To add a command: a module here that decorates its function with ``@app.command()`` (import heavy
modules inside the function), imported below.
"""

import flic_cli.cli.benchmark  # noqa: F401  (registers `flic benchmark`)
import flic_cli.cli.evaluate  # noqa: F401  (registers `flic evaluate`, `flic sweep-threshold`)
from flic_cli.cli import segment  # noqa: F401  (registers the commands)
from flic_cli.cli.app import app

__all__ = ["app"]

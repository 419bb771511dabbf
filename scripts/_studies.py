"""The command line of the study scripts (``scripts/*_study.py``): one subcommand per study.

Each study is a function of the parsed arguments whose docstring is its help (first line: the
summary in the list of studies) and a function that adds its arguments.
"""

from __future__ import annotations

import argparse
import inspect
from collections.abc import Callable

#: name -> (the study, the function that adds its arguments to its parser)
Studies = dict[
    str, tuple[Callable[[argparse.Namespace], None], Callable[[argparse.ArgumentParser], None]]
]


def run_studies(
    description: str | None,
    studies: Studies,
    argv: list[str] | None = None,
    common: Callable[[argparse.ArgumentParser], None] | None = None,
) -> None:
    """Parse ``argv`` (default: the command line) as ``STUDY [arguments]`` and run that study.

    Parameters
    ----------
    description : the script's help (its module docstring).
    studies : the subcommands.
    argv : the arguments (None: ``sys.argv[1:]``).
    common : adds the arguments every study takes, before its own (e.g. a positional DATA).
    """
    parser = argparse.ArgumentParser(
        description=description, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = parser.add_subparsers(dest="study", required=True, metavar="STUDY")
    for name, (run, add_arguments) in studies.items():
        doc = run.__doc__ or ""
        p = sub.add_parser(
            name,
            help=doc.splitlines()[0],
            description=inspect.cleandoc(doc),
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        if common is not None:
            common(p)
        add_arguments(p)
        p.set_defaults(run=run)
    args = parser.parse_args(argv)
    args.run(args)

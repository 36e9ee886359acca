"""Command line: ``gausspp demo`` (the main job), ``run``, ``verify``, ``report``, ``sweep`` and ``scenes``.

Exit codes: 0 success; 1 a gausspp error (a value the library rejects, a run that failed midway,
a file that cannot be written); 2 a malformed command line (unknown command, option, scene,
method, solver or scene parameter, a parameter value of the wrong type); 130 interrupted.
Errors print as one line on stderr (the traceback only with ``--debug``).

The grammar is :mod:`gausspp.cli.parser`, the subcommands :mod:`gausspp.cli.commands`; what they
compute and print comes from :mod:`gausspp.studies`.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Sequence

from ..errors import GaussppError
from ..studies.tables import one_line
from . import commands
from .console import EXIT_ERROR, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, UsageError
from .parser import build_parser, unknown_option

__all__ = ["EXIT_ERROR", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_USAGE", "COMMANDS", "UsageError", "main"]

#: Each subcommand's function: the parsed arguments → the exit code.
COMMANDS: dict[str, Callable[[argparse.Namespace], int]] = {
    "demo": commands.demo,
    "scenes": commands.list_scenes,
    "run": commands.run,
    "verify": commands.verify,
    "report": commands.report,
    "sweep": commands.sweep,
}


def _parse(argv: list[str]) -> argparse.Namespace | int:
    """The parsed arguments, or the exit code of ``--help`` (0) or of a usage error (2, already printed)."""
    parser = build_parser()
    try:
        unknown = unknown_option(parser, argv)
        if unknown is not None:
            unknown[0].error(f"unrecognized arguments: {unknown[1]}")
        return parser.parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``gausspp`` command: the exit code (0 ok, 1 error or failed run, 2 usage)."""
    args = _parse(list(sys.argv[1:] if argv is None else argv))
    if isinstance(args, int):
        return args
    try:
        return int(COMMANDS[args.command](args))
    except UsageError as exc:
        if args.debug:
            raise
        print(f"gausspp: error: {one_line(exc)} (see 'gausspp {args.command} --help')", file=sys.stderr)
        return EXIT_USAGE
    except GaussppError as exc:
        if args.debug:
            raise
        print(f"gausspp: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        if args.debug:
            raise
        print("gausspp: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader went away (`gausspp scenes | head`): nothing more to say, to anyone
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error when Python flushes
        return EXIT_OK
    except OSError as exc:  # a file or a directory the command could not write: what and where, no traceback
        if args.debug:
            raise
        where = f" {exc.filename!r}" if exc.filename else ""
        print(f"gausspp: error: cannot write{where}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_ERROR
    except Exception as exc:  # not foreseen by the library: still one line, the traceback with --debug
        if args.debug:
            raise
        print(
            f"gausspp: error: {type(exc).__name__}: {one_line(exc)} (unexpected: run with --debug for the traceback)",
            file=sys.stderr,
        )
        return EXIT_ERROR

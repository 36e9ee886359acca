"""The ``gausspp`` command line's grammar: subcommands, options, help texts, and usage errors as one line.

:func:`build_parser` returns the parser; each parsed namespace names its subcommand in ``command``.
:func:`unknown_option` finds an unknown option before argparse reports a missing argument.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from .. import scenes
from ..simulation import methods
from ..simulation.inputs import DEFAULT_ATOL, DEFAULT_RTOL
from ..step import qp
from ..step.solvers import SOLVERS
from ..studies.tables import one_line
from .console import EXIT_USAGE


class Parser(argparse.ArgumentParser):
    """argparse with usage errors as one line (``gausspp: error: ...``) and exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"gausspp: error: {one_line(message)} (see '{self.prog} --help')\n")


def _common() -> Parser:
    """Options every subcommand accepts too (after its name); absent there, the top-level value stands."""
    common = Parser(add_help=False)
    common.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help="show tracebacks")
    common.add_argument(
        "--quiet", action="store_true", default=argparse.SUPPRESS, help="no progress indication on stderr"
    )
    return common


def _positive(kind: type) -> Any:
    """An argparse type: a positive finite number of ``kind``."""

    def parse(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            value = None
        if value is None or not (value > 0 and np.isfinite(value)):
            raise argparse.ArgumentTypeError(
                f"expected a positive {'integer' if kind is int else 'number'}, got {text!r}"
            )
        return value

    return parse


def _simulation_options(p: argparse.ArgumentParser, rtol: float, samples: int) -> None:
    p.add_argument("scene", metavar="SCENE", choices=scenes.names(), help="a scene (see `gausspp scenes`)")
    p.add_argument(
        "-p",
        "--param",
        action="append",
        metavar="KEY=VALUE",
        help="a scene parameter, repeatable; VALUE is a Python literal (2.5, (1, 0, 0), None) or a word "
        "(servo); see `gausspp scenes SCENE` for the parameters",
    )
    p.add_argument(
        "--method",
        default="DOP853",
        choices=methods.names(),
        metavar="METHOD",
        help=f"integration method, one of {', '.join(methods.names())} (default: DOP853)",
    )
    p.add_argument("--t-end", type=_positive(float), metavar="T", help="final time (default: the scene's)")
    p.add_argument(
        "--dt",
        type=_positive(float),
        metavar="DT",
        help="step of fixed-step methods (default: T/2000); largest step of adaptive ones",
    )
    p.add_argument(
        "--rtol",
        type=_positive(float),
        default=rtol,
        metavar="R",
        help=f"relative tolerance of adaptive methods (default: {rtol:g})",
    )
    p.add_argument(
        "--atol",
        type=_positive(float),
        default=DEFAULT_ATOL,
        metavar="A",
        help="absolute tolerance of adaptive methods (default: rtol times each component's own size)",
    )
    p.add_argument(
        "--constraint-tol",
        type=_positive(float),
        default=1e-8,
        metavar="C",
        help="the accuracy a successful run keeps: each residual within C·(1 + |state|), the energy balance "
        "within 100·C of the energy scale; beyond it the run is 'drifted' (default: 1e-8)",
    )
    p.add_argument(
        "--samples",
        type=_positive(int),
        default=samples,
        metavar="N",
        help="record about N intervals: uniform times for adaptive methods, every k-th step otherwise "
        f"(default: {samples})",
    )


_EXIT_CODES = """\
exit codes: 0 success, 1 gausspp error or failed run, 2 bad command line."""

_EPILOG = (
    """\
examples:
  gausspp demo
  gausspp scenes two-masses
  gausspp run two-masses --param realization=servo --out results
  gausspp verify two-masses --param realization=ideal --check-param realization=servo

"""
    + _EXIT_CODES
)

_RUN = """\
Simulate SCENE and print a summary: status, steps, final state, constraint
residual, energy balance, realizability margin (and the error against the
exact motion where the scene knows it). With --out DIR, write DIR/SCENE.npz
(every array, the model's names, the run's settings), DIR/SCENE.csv and
DIR/SCENE.png; with --out FILE.npz or FILE.nc (netCDF, needs gausspp[data]),
that one file. Both read back by gausspp.load_trajectory (then gp.verify).
With --out FIG.png (or .svg, .pdf), only the figure of q(t) and v(t), labelled
with the scene's coordinates and units. A run that fails midway still writes
what it computed, then exits with 1.
With --animate FILE.gif (or .mp4), draw the mechanism moving (scenes that
carry a drawing; needs matplotlib).

examples:
  gausspp run two-masses --param realization=servo --param F=1
  gausspp run pendulum --animate pendulum.gif
  gausspp run rigid-body-servo -p "n=(1, 0.2, 0)" --method rk4 --dt 1e-3 --out results
  gausspp run skate -p realization=vakonomic --solver direct"""

_VERIFY = """\
Simulate SCENE (DOP853 with tight tolerances by default), then decide by the
integral principle (23) whether the path is a motion of the scene's model —
or, with --check-param, of the same scene built with other parameters (another
realization of the same constraint, say). Prints the relative gap, the
tolerance and the verdict; exit 0 when the verification ran, whatever the
verdict, unless --expect says otherwise.

examples:
  gausspp verify two-masses
  gausspp verify two-masses --param realization=ideal --check-param realization=servo
  gausspp verify skate --check-param realization=vakonomic --expect not-motion"""


_DEMO = """\
One step of the two-mass and rigid-body scenes by the direct formula and by
the Gauss QP, with the time per step; then every scene simulated with both
step solvers, their agreement along the run, the constraint residual, the
energy balance and the verdict of the integral principle (23); then the scenes
only the general Gauss QP can solve (contacts, saturation, extra actuators,
redundant rows); and four teaching figures in --out.

example:
  gausspp demo --out demo-figures"""

_REPORT = """\
Error against run time: every scene (or --scenes) with every integration
method and step solver, scored against the scene's exact solution or a finer
reference by another method; wall time is the minimum of --repeats runs.
Prints the table and the fastest run per scene reaching 1e-10, and writes
CSV/JSON and one work-precision plot per scene to --out. With --stability,
runs the stability study instead (stiff chain, mass ratios, small margins,
long horizon, redundant rows, data off the constraint, crane at the vertical
rope), with a verdict per case; exit 1 if a verdict fails.

examples:
  gausspp report --scenes pendulum
  gausspp report --stability"""

_SWEEP = """\
Run a sweep on local worker processes. With --out every result is appended as
it arrives, and a second run with the same --out resumes: tasks already
recorded are not run again. For a dask cluster use gausspp.sweep from Python.

examples:
  gausspp sweep realizability --resolution 1 --out margins.jsonl
  gausspp sweep work-precision --out report
  gausspp sweep work-precision --scenes pendulum crane --methods rk4 DOP853 --solvers direct"""


def _add_demo(sub: Any, common: Parser) -> None:
    """``gausspp demo``."""
    dem = sub.add_parser(
        "demo",
        parents=[common],
        help="the main job: every scene by QP and direct, a table, figures",
        description=_DEMO,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    dem.add_argument("--out", default="demo-figures", help="directory for the figures (default: demo-figures/)")


def _add_scenes(sub: Any, common: Parser) -> None:
    """``gausspp scenes [SCENE]``."""
    sc = sub.add_parser(
        "scenes",
        parents=[common],
        help="list the scenes, or show one scene's parameters",
        description="List the scenes with a one-line description, or show one scene's description and parameters.",
    )
    sc.add_argument("name", nargs="?", metavar="SCENE", choices=scenes.names(), help="show this scene's parameters")


def _add_run(sub: Any, common: Parser) -> None:
    """``gausspp run SCENE``."""
    r = sub.add_parser(
        "run",
        parents=[common],
        help="simulate a scene: a summary, and the trajectory as files with --out",
        description=_RUN,
        epilog=_EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _simulation_options(r, rtol=DEFAULT_RTOL, samples=500)
    r.add_argument(
        "--solver",
        choices=SOLVERS,
        help="each step by the Gauss QP or the direct formula (default: qp; direct for cvodes)",
    )
    r.add_argument(
        "--backend",
        metavar="B",
        help=f"QP backend for --solver qp (default: {qp.DEFAULT}); e.g. casadi:osqp, qpsolvers:daqp",
    )
    r.add_argument(
        "--stabilize",
        choices=("none", "project", "baumgarte"),
        default=None,
        help="drift control (default: the scene's own, e.g. the saturated crane's feedback; else none)",
    )
    r.add_argument(
        "--out",
        metavar="PATH",
        help="write the trajectory: to the directory PATH (NPZ, CSV and, with matplotlib, PNG), or to one file "
        "PATH ending .npz or .nc (netCDF); read back by gausspp.load_trajectory",
    )
    r.add_argument(
        "--animate",
        metavar="FILE",
        help="draw the mechanism moving into FILE (.gif, or .mp4 with ffmpeg; needs matplotlib); scenes with a "
        "drawing: pendulum, two-masses, overhead-crane, ...",
    )


def _add_verify(sub: Any, common: Parser) -> None:
    """``gausspp verify SCENE``."""
    v = sub.add_parser(
        "verify",
        parents=[common],
        help="simulate a scene and decide by (23) whether the path is a motion",
        description=_VERIFY,
        epilog=_EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _simulation_options(v, rtol=1e-10, samples=400)
    v.add_argument(
        "-c",
        "--check-param",
        action="append",
        metavar="KEY=VALUE",
        help="build the model to check against with this parameter changed (repeatable)",
    )
    v.add_argument("--expect", choices=("motion", "not-motion"), help="exit with 1 if the verdict is not this")


def _add_report(sub: Any, common: Parser) -> None:
    """``gausspp report``."""
    rep = sub.add_parser(
        "report",
        parents=[common],
        help="error against run time for every scene, method and solver",
        description=_REPORT,
        epilog=_EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    rep.add_argument("--stability", action="store_true", help="run the stability study instead")
    rep.add_argument("--full", action="store_true", help="finer sweeps (and full-size stability cases)")
    rep.add_argument("--scenes", nargs="*", metavar="SCENE", choices=scenes.names(), help="only these scenes")
    rep.add_argument("--repeats", type=int, default=2, help="timing repeats (the minimum is kept)")
    rep.add_argument("--out", default="report", help="directory for CSV/JSON and plots (default: report/)")
    rep.add_argument("--verbose", action="store_true", help="progress on stderr")


def _add_sweep(sub: Any, common: Parser) -> None:
    """``gausspp sweep STUDY``."""
    swp = sub.add_parser(
        "sweep",
        parents=[common],
        help="a parameter sweep on all local cores, saved as it runs (resumable)",
        description=_SWEEP,
        epilog=_EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    swp.add_argument(
        "study",
        choices=("realizability", "work-precision"),
        help="realizability: the servo margin over the sphere of n; work-precision: the report's error against "
        "run time, one task per run",
    )
    swp.add_argument(
        "--workers",
        type=_positive(int),
        default=os.cpu_count() or 1,
        metavar="N",
        help="worker processes (default: all; 1 runs in this process)",
    )
    swp.add_argument(
        "--out",
        metavar="PATH",
        help="realizability: a JSON-lines FILE of results (appended; resumes). work-precision: a DIRECTORY "
        "(default: report/) for work_precision.jsonl (the resumable log), the CSV/JSON and the plots",
    )
    swp.add_argument(
        "--resolution",
        type=float,
        metavar="R",
        help="realizability: grid step in degrees (default: 2)",
    )
    swp.add_argument(
        "--scenes", nargs="+", metavar="SCENE", choices=scenes.names(), help="work-precision: only these scenes"
    )
    swp.add_argument(
        "--methods",
        nargs="+",
        metavar="METHOD",
        choices=methods.names(),
        help="work-precision: only these methods (default: rk4 DOP853 Radau cvodes)",
    )
    swp.add_argument(
        "--solvers",
        nargs="+",
        metavar="SOLVER",
        help=f"work-precision: direct and/or QP backends (default: direct {qp.DEFAULT} casadi:osqp)",
    )
    swp.add_argument(
        "--full", action="store_true", default=None, help="work-precision: finer sweeps of steps and tolerances"
    )
    swp.add_argument(
        "--repeats", type=_positive(int), metavar="N", help="work-precision: timing repeats, the minimum is kept (2)"
    )


def build_parser() -> argparse.ArgumentParser:
    """The ``gausspp`` parser; the parsed namespace names its subcommand in ``command``."""
    common = _common()
    parser = Parser(
        prog="gausspp",
        description="Constrained mechanics by Gauss's principle of least constraint, with servo-constraints.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    parser.add_argument("--quiet", action="store_true", help="no progress indication on stderr")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in (_add_demo, _add_scenes, _add_run, _add_verify, _add_report, _add_sweep):
        add(sub, common)
    return parser


def unknown_option(parser: argparse.ArgumentParser, argv: Sequence[str]) -> tuple[argparse.ArgumentParser, str] | None:
    """The first option in ``argv`` that neither ``parser`` nor the subcommand named in ``argv`` knows, with the
    parser it was given to. argparse reports a missing argument (``COMMAND``, ``SCENE``) before an unknown option,
    which misleads when the option is the mistake (``gausspp --bogus-flag``)."""
    commands = next((a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction)), {})
    current = parser
    for token in argv:
        if token == "--":
            break
        if current is parser and token in commands:
            current = commands[token]
            continue
        if not token.startswith("-") or token == "-" or _is_number(token):
            continue
        known = [s for action in current._actions for s in action.option_strings]
        name = token.partition("=")[0]
        if token.startswith("--"):  # a long option, or an unambiguous abbreviation of one
            ok = any(k.startswith(name) for k in known if k.startswith("--"))
        else:  # a short option, with its value attached (-pKEY=VALUE) or not
            ok = any(token.startswith(k) for k in known if not k.startswith("--"))
        if not ok:
            return current, token
    return None


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True

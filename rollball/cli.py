"""The ``rollball`` command line.

Exit status: 0 when a run reached its end (a lift-off is a warning), 1 when the physics
stopped it early (the trajectory up to there is still written), 2 for bad input or usage,
141 when the reader of the output went away (``rollball examples | head -1``), as for
programs that SIGPIPE ends. Messages are one line on stderr; user-controlled text in them
(file names, JSON keys) is escaped.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from pathlib import Path

from . import __version__
from .examples import example_scenes
from .files import write_target
from .scene import SceneError
from .tableaus import METHODS
from .text import shown

EXIT_OK, EXIT_STOPPED, EXIT_BAD_INPUT, EXIT_BROKEN_PIPE = 0, 1, 2, 141
STDOUT = "-"


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # usage errors: one line, exit 2
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 and value != float("inf")):
        raise argparse.ArgumentTypeError(f"must be a finite number greater than 0: {text!r}")
    return value


def _positive_int(text: str) -> int:
    if len(text.strip()) > 30:
        raise argparse.ArgumentTypeError(f"number too large ({len(text)} characters)")
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be 1 or more: {text!r}")
    return value


def _output_file(text: str) -> str:
    if text == "":
        raise argparse.ArgumentTypeError("empty file name (use - for standard output)")
    return text


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="rollball",
        description="Simulate a solid ball rolling without slipping over a landscape z = f(x, y).",
        epilog="Example: rollball simulate resources/examples/hills.json --csv hills.csv",
    )
    parser.add_argument("--version", action="version", version=f"rollball {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    sim = commands.add_parser(
        "simulate", help="run a scene file and print a one-line summary",
        description="Run a scene file (JSON) and print a one-line summary: steps, status, "
                    "relative energy drift and the first lift-off time. Options override the scene.")
    sim.add_argument("scene", metavar="SCENE.json", help="scene file to run")
    sim.add_argument("--method", choices=list(METHODS),
                     help="Runge-Kutta method; adaptive: Dormand-Prince 5(4) steps that keep to "
                          "--rtol/--atol, always Munthe-Kaas")
    mk = sim.add_mutually_exclusive_group()
    mk.add_argument("--munthe-kaas", dest="munthe_kaas", action="store_true", default=None,
                    help="advance the orientation on SO(3) (Runge-Kutta-Munthe-Kaas)")
    mk.add_argument("--classic", dest="munthe_kaas", action="store_false",
                    help="integrate the orientation as a plain 3x3 matrix, as in 2011")
    sim.add_argument("--dt", type=_positive_float, metavar="H",
                     help="step size (s); for adaptive the first step tried")
    sim.add_argument("--t-end", type=_positive_float, metavar="T", help="end time (s)")
    sim.add_argument("--every", type=_positive_int, default=1, metavar="N",
                     help="record every N-th step (default 1; fixed steps)")
    sim.add_argument("--rtol", type=_positive_float, metavar="R", help="relative tolerance (adaptive)")
    sim.add_argument("--atol", type=_positive_float, metavar="A", help="absolute tolerance (adaptive)")
    sim.add_argument("--record-dt", type=_positive_float, metavar="T",
                     help="record at multiples of T seconds and at the end (adaptive; "
                          "default: every accepted step)")
    sim.add_argument("--csv", metavar="OUT.csv", type=_output_file,
                     help="write the trajectory as CSV (- for standard output; the summary then "
                          "goes to standard error)")

    commands.add_parser("examples", help="list the example scenes",
                        description="List the example scenes shipped with RollBall.")

    bench = commands.add_parser(
        "bench", help="measure speed against error (work-precision report)",
        description="Measure the speed targets (kernel step against C, real-time factor, "
                    "new-formula latency, cold start, memory) and the error against wall time "
                    "and steps of every method on example scenes, with scipy's DOP853 as the "
                    "baseline. Writes bench.md, bench.png and bench.json.")
    bench.add_argument("--quick", action="store_true", help="a smaller run (under a minute)")
    bench.add_argument("--out", metavar="DIR", default=".", help="output folder (default: .)")
    return parser


def _simulate(args) -> int:
    from .scene import Scene
    from .simulation import simulate
    from .trajectory import Status

    name = shown(args.scene)
    try:
        scene = Scene.load(args.scene)
    except (SceneError, OSError) as e:
        return _fail(f"{name}: {e.strerror if isinstance(e, OSError) and e.strerror else e}")
    to_stdout = args.csv == STDOUT
    if args.csv and not to_stdout:
        try:  # before the run: a refused target must not cost the run
            write_target(args.csv, keep=[args.scene])
        except OSError as e:
            return _fail(f"cannot write {shown(args.csv)}: {e.strerror or e}")
    try:
        traj = simulate(scene, method=args.method, munthe_kaas=args.munthe_kaas, dt=args.dt,
                        t_end=args.t_end, record_every=args.every, rtol=args.rtol, atol=args.atol,
                        record_dt=args.record_dt)
    except ValueError as e:  # includes FormulaError
        return _fail(str(e))
    liftoff = ("no lift-off" if traj.liftoff_time is None
               else f"WARNING: lift-off at t = {traj.liftoff_time:.6g} s (the real ball would leave the surface)")
    print(f"{name}: {traj.steps} steps, status {traj.status} ({traj.message}), "
          f"relative energy drift {traj.energy_drift:.3g}, {liftoff}",
          file=sys.stderr if to_stdout else sys.stdout)
    if to_stdout:
        traj.write_csv(sys.stdout)
    elif args.csv:
        try:
            traj.to_csv(args.csv, keep=[args.scene])
        except OSError as e:
            return _fail(f"cannot write {shown(args.csv)}: {e.strerror or e}")
    return EXIT_OK if traj.status is Status.OK else EXIT_STOPPED


def _examples() -> int:
    for path, scene in example_scenes():
        try:
            path = path.relative_to(Path.cwd())
        except ValueError:
            pass
        print(f"{shown(path)}: {shown(scene.description)}")
    return EXIT_OK


def _bench(args) -> int:
    try:
        import scipy  # noqa: F401
    except ImportError:
        return _fail("the benchmark needs scipy: pip install 'rollball[bench]'")
    from . import bench

    log = lambda text: print(text, file=sys.stderr)  # noqa: E731
    try:
        print(bench.run(Path(args.out), bench.QUICK if args.quick else bench.FULL, log=log))
    except OSError as e:
        return _fail(f"cannot write to {shown(args.out)}: {e.strerror or e}")
    return EXIT_OK


def _fail(message: str) -> int:
    print(f"rollball: error: {message}", file=sys.stderr)
    return EXIT_BAD_INPUT


def _warning(message, category, filename, lineno, file=None, line=None):
    """A warning as one line of its own (the summary stays one line)."""
    print(f"rollball: warning: {' '.join(str(message).split())}", file=sys.stderr)


COMMANDS = {"simulate": _simulate, "examples": lambda args: _examples(), "bench": _bench}


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command not in COMMANDS:
        parser.print_help()
        return EXIT_BAD_INPUT
    with warnings.catch_warnings():
        warnings.showwarning = _warning
        # overflow or invalid values in derived columns are reported by the run's status
        warnings.filterwarnings("ignore", category=RuntimeWarning)
        try:
            code = COMMANDS[args.command](args)
            sys.stdout.flush()
        except KeyboardInterrupt:
            print("rollball: interrupted", file=sys.stderr)
            return 130
        except BrokenPipeError:  # the reader left (| head): stop quietly, as SIGPIPE would
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return EXIT_BROKEN_PIPE
    return code

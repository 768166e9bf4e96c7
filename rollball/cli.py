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

# Only what the parser needs, none of it numerical: the help and a refused argument answer at
# once; each command imports the simulation, sympy, numba or scipy it runs on (a test holds this).
from . import __version__
from .examples import EXAMPLES_DIR, example_descriptions, scene_path, track_path
from .files import replace_together, write_target
from .fit_options import LENGTH_UNITS, LOSSES, NOT_FITTED, POINTS, TIME_UNITS
from .kinds import KINDS, MethodKind, method_name
from .sweeps.options import CONNECT_TIMEOUT as SWEEP_CONNECT_TIMEOUT
from .sweeps.options import KEYS as SWEEP_KEYS
from .sweeps.options import WORKER_TIMEOUT as SWEEP_WORKER_TIMEOUT
from .text import shown

EXIT_OK, EXIT_STOPPED, EXIT_BAD_INPUT, EXIT_BROKEN_PIPE = 0, 1, 2, 141
STDOUT = "-"
FIT_KEPT_NAME = "fit-unsaved"   # where a fit's files that could not replace the old ones are kept


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


def _method(text: str) -> str:
    try:
        return method_name(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


# Scene values ``simulate`` overrides (version 4): flag, dotted key, metavar, help. The text is
# handed to the scene as it is given, so that the scene refuses a bad one naming its key.
SCENE_FLAGS = (
    ("--rolling-resistance", "contact.rolling_resistance", "C",
     "rolling resistance c_rr >= 0: a couple c_rr r F_n against the rolling"),
    ("--spin-friction", "contact.spin_friction", "M",
     "spin friction mu_s >= 0: a couple mu_s r F_n against the spin about the normal"),
    ("--air-density", "air.density", "RHO", "air density in kg/m3 (air 1.2), with --drag-coefficient"),
    ("--drag-coefficient", "air.drag_coefficient", "CD",
     "drag coefficient (a smooth sphere 0.47), with --air-density"),
)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="rollball",
        description="Simulate a solid ball rolling, sliding and flying over a landscape z = f(x, y).",
        epilog="Example: rollball simulate hills --csv hills.csv (an example by name, or a scene file)",
    )
    parser.add_argument("--version", action="version", version=f"rollball {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    sim = commands.add_parser(
        "simulate", help="run a scene file and print a one-line summary",
        description="Run a scene file (JSON) and print a one-line summary: steps, status, "
                    "relative energy drift and the first lift-off time. Options override the scene.")
    sim.add_argument("scene", metavar="SCENE", help="scene file to run, or an example's name (rollball examples)")
    adaptive = ", ".join(name for name, kind in KINDS.items() if kind is MethodKind.ADAPTIVE)
    sim.add_argument("--method", type=_method, metavar="{" + ",".join(KINDS) + "}",
                     help=f"Runge-Kutta method; adaptive ones ({adaptive}) choose their steps to keep "
                          "to --rtol/--atol, always Munthe-Kaas")
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
    for flag, key, metavar, text in SCENE_FLAGS:
        sim.add_argument(flag, dest=key, metavar=metavar, help=f"{text} ({key})")
    rest = sim.add_mutually_exclusive_group()
    rest.add_argument("--stop-at-rest", dest="stop_at_rest", action="store_true", default=None,
                      help="end the run where the ball comes to rest (stop_at_rest; by default the scene says)")
    rest.add_argument("--no-stop-at-rest", dest="stop_at_rest", action="store_false",
                      help="go on to the end time in mode resting once the ball is at rest")
    sim.add_argument("--csv", metavar="OUT.csv", type=_output_file,
                     help="write the trajectory as CSV (- for standard output; the summary then "
                          "goes to standard error)")

    sweep = commands.add_parser(
        "sweep", help="run a scene over a grid of values: one row of outcomes per run",
        description="Run a scene once for every combination of the varied values (the last "
                    "--vary varies fastest) and write sweep.csv (one row per run: the varied "
                    "values, status, then the outcomes t_reached, liftoff_time, x_end, y_end, "
                    "energy_drift, min_normal_force, max_speed, path_length and, of the contact, "
                    "end_mode (rolling, sliding, flying or resting), landings, first_slip_time and "
                    "first_grip_time, and of a ball that comes to rest rest_x, rest_y, rest_time and "
                    "basin: the number of the landscape's local minimum its steepest descent from there "
                    "reaches, 1 the lowest, 0 none), sweep.json (with the minima: number, x, y, f) and "
                    "sweep.png (a map coloured by one outcome, --color basin a colour per minimum, "
                    "or each outcome against one varied key). "
                    "Local on every core by default; --scheduler sends the runs to a Dask "
                    "cluster. Ctrl-C stops and writes the runs finished so far.")
    sweep.add_argument("scene", metavar="SCENE.json", help="scene file (a fixed-step method)")
    sweep.add_argument("--vary", action="append", required=True, metavar="KEY=START:STOP:N",
                       help=f"N evenly spaced values from START to STOP (both included); "
                            f"repeat for a grid. KEY: {', '.join(SWEEP_KEYS)}, or parameters.NAME (a parameter of "
                            f"the scene's formula)")
    sweep.add_argument("--color", default="liftoff_time", metavar="OUTCOME",
                       help="the outcome the map of two varied keys is coloured by "
                            "(default liftoff_time; basin: a colour per minimum)")
    where = sweep.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_positive_int, metavar="N",
                       help="local workers (default: every core): threads, or processes for "
                            "runs that can come to rest (each one a Simulation)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="a Dask distributed scheduler, e.g. tcp://10.0.0.5:8786 "
                            "(needs pip install 'rollball[dask]')")
    sweep.add_argument("--connect-timeout", type=_positive_float, default=SWEEP_CONNECT_TIMEOUT, metavar="S",
                       help=f"with --scheduler: seconds for the scheduler to answer "
                            f"(default {SWEEP_CONNECT_TIMEOUT:g})")
    sweep.add_argument("--worker-timeout", type=_positive_float, default=SWEEP_WORKER_TIMEOUT, metavar="S",
                       help=f"with --scheduler: seconds to wait for a first worker, or for one to come "
                            f"back when all left (default {SWEEP_WORKER_TIMEOUT:g})")
    sweep.add_argument("--out", metavar="DIR", default=".", help="output folder (default: .)")

    cmp = commands.add_parser(
        "compare", help="speed against error of every method on a scene",
        description="Run every method (or the --runs given) over a ladder of step sizes or "
                    "tolerances on a scene, measure each run's error against a tight reference and "
                    "its compute time, fit the orders, and write compare.json, compare.md and "
                    "compare.png. Ends with the fastest run for errors of 1e-6 and 1e-10.")
    cmp.add_argument("scene", metavar="SCENE.json", help="scene file (or an example's name)")
    cmp.add_argument("--runs", metavar="SPECS",
                     help="comma-separated METHOD or METHOD/classic (default: every method, the "
                          "fixed-step ones Munthe-Kaas and classic), e.g. euler/classic,rk4,dopri5")
    cmp.add_argument("--t-end", type=_positive_float, metavar="T", help="end time (s; default: the scene's)")
    cmp.add_argument("--quick", action="store_true", help="fewer, shorter ladders (under a minute)")
    cmp.add_argument("--out", metavar="DIR", default=".", help="output folder (default: .)")

    check = commands.add_parser(
        "check", help="a measured track against a run of a scene: residuals",
        description="Run a scene to a measured track's last time and print the residuals (the track "
                    "minus the ball's centre, or its contact point, at the track's times): RMS, largest, "
                    "per axis, against the track's noise, and whether the model explains the track.")
    _track_arguments(check)

    fit = commands.add_parser(
        "fit", help="fit scene values to a measured track (least squares)",
        description="Fit scene values (start, ball, contact, gravity, parameters) to a measured track "
                    "by least squares from the scene's values, and print each estimate with its "
                    "standard error, the correlations, the residuals against the track's noise and the "
                    "number of runs.")
    _track_arguments(fit)
    fit.add_argument("--fit", required=True, metavar="KEYS",
                     help=f"comma-separated keys to fit: {', '.join(k for k in SWEEP_KEYS if k not in NOT_FITTED)}, "
                          f"or parameters.NAME; e.g. contact.friction,start.vx")
    fit.add_argument("--bounds", action="append", default=[], metavar="KEY=LO:HI",
                     help="bounds of a fitted key (LO or HI may be empty: unbounded); by default a value's "
                          "valid range (friction >= 0, restitution 0 to 1, a parameter's min and max)")
    fit.add_argument("--loss", choices=LOSSES, default="linear",
                     help="linear: least squares (default); the others are robust, scaled by the noise: "
                          "far-off positions (wrongly tracked frames) count less")
    fit.add_argument("--out", metavar="FITTED.json", type=_output_file,
                     help="write the scene with the fitted values")

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


def _track_arguments(parser) -> None:
    """The arguments ``check`` and ``fit`` share: the scene, the track and how to read it."""
    parser.add_argument("scene", metavar="SCENE", help="scene file, or an example's name")
    parser.add_argument("track", metavar="TRACK", help="CSV or TSV: a header naming t and two or three of "
                        "x, y, z (units as x (cm) or by option), Tracker's export too")
    parser.add_argument("--columns", metavar="AXIS=COLUMN,...",
                        help="the file's columns for the scene's axes (and t), e.g. x=x,z=y for a side view "
                             "(default: the columns named t, x, y, z)")
    parser.add_argument("--length-unit", choices=LENGTH_UNITS,
                        help="unit of the positions whose header names none (default m)")
    parser.add_argument("--time-unit", choices=TIME_UNITS,
                        help="unit of the times if the header names none (default s)")
    parser.add_argument("--point", choices=POINTS, default="center",
                        help="the point of the ball the track follows (default center)")
    parser.add_argument("--noise", type=_positive_float, metavar="METRES",
                        help="the track's noise, one coordinate's standard deviation (default: estimated "
                             "from the track)")
    parser.add_argument("--plot", metavar="RESIDUALS.png", type=_output_file,
                        help="write a figure of the residuals against time")


def _load_scene(name: str):
    """The scene of a file or an example's name, or (after a one-line message) exit status 2."""
    from .scene import Scene, SceneError

    try:
        return Scene.load(scene_path(name))
    except FileNotFoundError as e:
        return _fail(f"{shown(e.filename or name)}: {e.strerror}" if e.strerror else str(e))
    except (SceneError, OSError) as e:
        return _fail(f"{shown(name)}: {e.strerror if isinstance(e, OSError) and e.strerror else e}")


def _simulate(args) -> int:
    from .scene import Scene
    from .simulation import simulate
    from .trajectory import Status
    from .warmup import compile_notice

    scene = _load_scene(args.scene)
    if not isinstance(scene, Scene):
        return scene
    scene = _overridden(scene, args)
    if not isinstance(scene, Scene):
        return scene
    to_stdout = args.csv == STDOUT
    if args.csv and not to_stdout:
        try:  # before the run: a refused target must not cost the run
            write_target(args.csv, keep=[scene_path(args.scene)])
        except OSError as e:
            return _fail(f"cannot write {shown(args.csv)}: {e.strerror or e}")
    try:
        with compile_notice(lambda: print("rollball: compiling the integrator, first run only ...",
                                          file=sys.stderr, flush=True)):
            traj = simulate(scene, method=args.method, munthe_kaas=args.munthe_kaas, dt=args.dt,
                            t_end=args.t_end, record_every=args.every, rtol=args.rtol, atol=args.atol,
                            record_dt=args.record_dt)
    except ValueError as e:  # includes FormulaError
        return _fail(str(e))
    flew = any(change.kind == "liftoff" for change in traj.transitions)
    liftoff = ("no lift-off" if traj.liftoff_time is None
               else f"first lift-off at t = {traj.liftoff_time:.6g} s" if flew
               else f"WARNING: lift-off at t = {traj.liftoff_time:.6g} s (the real ball would leave the surface)")
    warnings = "".join(f", WARNING: {note}" for note in traj.warnings())
    lost = f", {traj.dissipated[-1]:.4g} J dissipated" if len(traj) and traj.dissipated[-1] else ""
    out = sys.stderr if to_stdout else sys.stdout
    print(f"{shown(args.scene)}: {traj.steps} steps ({traj.rejected} rejected, {traj.evaluations} evaluations), "
          f"status {traj.status} ({traj.message}), "
          f"relative energy drift {traj.energy_drift:.3g}, {liftoff}{lost}{warnings}", file=out)
    for change in traj.transitions:
        print(f"  {change.sentence()}", file=out)
    if to_stdout:
        traj.write_csv(sys.stdout)
    elif args.csv:
        try:
            traj.to_csv(args.csv, keep=[scene_path(args.scene)])
        except OSError as e:
            return _fail(f"cannot write {shown(args.csv)}: {e.strerror or e}")
    return EXIT_OK if traj.status is Status.OK else EXIT_STOPPED


def _overridden(scene, args):
    """The scene with the values its flags give (``SCENE_FLAGS``, --no-stop-at-rest), or (after a
    one-line message naming the flag and the key) exit status 2."""
    import dataclasses

    from .scene import SceneError
    from .sweeps.grid import with_values

    given = {key: getattr(args, key) for _, key, _, _ in SCENE_FLAGS if getattr(args, key) is not None}
    values = {key: _number_or_text(text) for key, text in given.items()}
    try:
        if args.stop_at_rest is not None:
            scene = dataclasses.replace(scene, stop_at_rest=args.stop_at_rest)
        return with_values(scene, list(values), list(values.values()))
    except SceneError as e:
        named = [flag for flag, key, _, _ in SCENE_FLAGS if key in given and key == e.key] or [
            flag for flag, key, _, _ in SCENE_FLAGS if key in given]   # (air's other half: what was given)
        return _fail(f"{' '.join(named)}: {e}")


def _number_or_text(text: str):
    """A flag's number, or its text as given (the scene refuses it naming the key)."""
    try:
        return float(text)
    except ValueError:
        return text


def _sweep(args) -> int:
    import signal
    import threading

    from tqdm import tqdm

    from .files import NotReplaced
    from .scene import Scene
    from .sweeps import OUTCOMES, Grid, parse_vary, sweep
    from .sweeps.grid import check_keys
    from .sweeps import table as sweep_files

    try:
        grid = Grid.of([parse_vary(text) for text in args.vary])
    except ValueError as e:
        return _fail(str(e))
    if args.color not in OUTCOMES:
        return _fail(f"--color {shown(args.color)}: not an outcome; the outcomes: {', '.join(OUTCOMES)}")
    if args.scheduler is not None:
        from .sweeps.runner import check_address

        try:
            check_address(args.scheduler)
        except ValueError as e:
            return _fail(shown(str(e)))
    scene = _load_scene(args.scene)
    if not isinstance(scene, Scene):
        return scene
    try:
        check_keys(scene, grid.keys)   # parameters.NAME: the scene must declare NAME
    except ValueError as e:
        return _fail(str(e))
    out = Path(args.out)
    try:  # before the first run: a refused folder or file must not cost the runs
        sweep_files.check(out, keep=[scene_path(args.scene)])
    except OSError as e:
        return _fail(f"cannot write to {shown(e.filename or out)}: {e.strerror or e}")
    failure = _compiles(scene)
    if failure:
        return _fail(failure)

    cancel = threading.Event()

    def interrupted(signum, frame):
        cancel.set()
        signal.signal(signal.SIGINT, signal.default_int_handler)  # a second Ctrl-C aborts at once
        print("\nrollball: stopping after the batches under way (Ctrl-C again to abort)", file=sys.stderr)

    bar = tqdm(total=grid.size, unit="run", file=sys.stderr, smoothing=0.1, dynamic_ncols=True)

    def progress(done, total, text):
        bar.update(done - bar.n)

    previous = signal.signal(signal.SIGINT, interrupted)
    try:
        table = sweep(scene, dict(zip(grid.keys, grid.axes)), workers=args.workers,
                      scheduler=args.scheduler, progress=progress, cancel=cancel,
                      connect_timeout=args.connect_timeout, worker_timeout=args.worker_timeout)
    except ValueError as e:
        bar.close()  # first, so that the message is a line of its own
        return _fail(str(e))
    except KeyboardInterrupt:
        bar.close()
        print("rollball: interrupted", file=sys.stderr)
        return 130
    finally:
        signal.signal(signal.SIGINT, previous)
        bar.close()
    done = int(table.done.sum())
    try:
        files = table.save(out, args.color)
    except NotReplaced as e:
        return _fail(f"cannot write {shown(e.filename or out)}: {e.strerror or e}")
    except OSError as e:
        return _fail(f"cannot write {shown(e.filename or out)}: {e.strerror or e}; "
                     f"none of {', '.join(sweep_files.FILES)} was replaced")
    counts = ", ".join(f"{n:,} {name}" for name, n in table.counts().items())
    where = (f"Dask workers at {table.scheduler}" if table.scheduler
             else "local processes" if table.processes else "local threads")
    print(f"{done:,} of {len(table):,} runs in {table.seconds:.3g} s "
          f"({done / max(table.seconds, 1e-9):,.0f} runs/s on {table.workers} {where}): {counts}; "
          f"wrote {', '.join(str(f) for f in files)}")
    if table.error:
        print(f"rollball: error: {table.error}; sweep.csv holds the {done:,} runs finished", file=sys.stderr)
        return EXIT_STOPPED
    if table.partial:
        print(f"rollball: stopped early; sweep.csv holds the {done:,} runs finished "
              f"(sweep.json says partial)", file=sys.stderr)
        return 130
    return EXIT_OK


def _compare(args) -> int:
    from .run_specs import parse_runs

    try:  # before the numerical modules load: a bad spec is refused at once
        runs = None if args.runs is None else parse_runs(args.runs)
    except ValueError as e:
        return _fail(str(e))

    from tqdm import tqdm

    from . import comparison_report
    from .comparison import NothingToCompare, compare
    from .files import NotReplaced
    from .scene import Scene

    scene = _load_scene(args.scene)
    if not isinstance(scene, Scene):
        return scene
    keep = [scene_path(args.scene)]
    try:  # before the first run: a refused folder or file must not cost the runs
        comparison_report.check(Path(args.out), keep)
    except OSError as e:
        return _fail(f"cannot write to {shown(e.filename or args.out)}: {e.strerror or e}")
    failure = _compiles(scene)
    if failure:
        return _fail(failure)
    with tqdm(total=1, file=sys.stderr, unit="run", dynamic_ncols=True, leave=False) as bar:
        def progress(done: int, total: int, text: str) -> None:
            bar.total = total
            bar.n = done
            bar.set_description_str(text, refresh=False)
            bar.refresh()

        try:
            result = compare(scene, runs=runs, t_end=args.t_end, quick=args.quick, progress=progress)
        except NothingToCompare as e:
            print(f"rollball: {shown(args.scene)}: {e}", file=sys.stderr)
            return EXIT_STOPPED
        except ValueError as e:  # includes FormulaError
            return _fail(str(e))
    stopped = sum(not r.ok for r in result.runs)
    note = f"; {stopped} runs stopped early (see compare.md)" if stopped else ""
    print(f"{shown(args.scene)}: {len(result.runs)} runs to t = {result.t_end:g} s{note}; {result.summary()}",
          flush=True)
    try:
        written = comparison_report.save(result, args.out, keep)
    except NotReplaced as e:
        return _fail(f"cannot write {shown(e.filename or args.out)}: {e.strerror or e}")
    except OSError as e:
        return _fail(f"cannot write {shown(e.filename or args.out)}: {e.strerror or e}; "
                     f"none of {', '.join(comparison_report.FILES)} was replaced")
    print(f"wrote {', '.join(shown(p) for p in written)}")
    return EXIT_OK


def _load_track(args):
    """The track file the arguments name, or (after a one-line message) exit status 2."""
    from .track import Track, TrackError, parse_columns

    try:
        columns = None if args.columns is None else parse_columns(args.columns)
        return Track.load(track_path(args.track), columns=columns, length_unit=args.length_unit,
                          time_unit=args.time_unit)
    except OSError as e:
        return _fail(f"{shown(e.filename or args.track)}: {e.strerror or e}")
    except (TrackError, ValueError) as e:
        return _fail(str(e))


def _measured(args, outputs):
    """(scene, track) for check and fit, their outputs checked before any run; or an exit status."""
    from .scene import Scene

    scene = _load_scene(args.scene)
    if not isinstance(scene, Scene):
        return scene
    track = _load_track(args)
    if isinstance(track, int):
        return track
    named = [path for path in outputs if path]
    if len(set(map(os.path.abspath, named))) < len(named):
        return _fail(f"the outputs must be different files: {', '.join(map(shown, named))}")
    if len({os.path.dirname(os.path.abspath(path)) for path in named}) > 1:   # replaced together: one folder
        return _fail(f"the outputs must be in one folder (they are replaced together or not at all): "
                     f"{', '.join(map(shown, named))}")
    for path in named:
        try:  # before the runs: a refused target must not cost them
            write_target(path, keep=[scene_path(args.scene), track_path(args.track)])
        except OSError as e:
            return _fail(f"cannot write {shown(path)}: {e.strerror or e}")
    failure = _compiles(scene)
    if failure:
        return _fail(failure)
    return scene, track


def _write_plot(args, res, title: str) -> int | None:
    """The residuals' figure at --plot (if asked), or an exit status after a one-line message."""
    from .files import atomic_write_bytes
    from .residual_plot import figure_png

    if not args.plot:
        return None
    png = figure_png(res, title)
    if png is None:
        return _fail("cannot draw the residuals: matplotlib is not installed")
    try:
        atomic_write_bytes(args.plot, png, keep=[scene_path(args.scene), track_path(args.track)])
    except OSError as e:
        return _fail(f"cannot write {shown(args.plot)}: {e.strerror or e}")
    return None


def _heading(args, track) -> str:
    skipped = f", {track.skipped} rows without a position skipped" if track.skipped else ""
    return (f"{shown(args.track)}: {len(track)} positions ({', '.join(track.axes)}) from t = {track.t[0]:.6g} "
            f"to {track.t[-1]:.6g} s{skipped}; the ball's {args.point}, scene {shown(args.scene)}")


def _check(args) -> int:
    from .track_check import residuals

    loaded = _measured(args, [args.plot])
    if isinstance(loaded, int):
        return loaded
    scene, track = loaded
    try:
        res = residuals(scene, track, args.point, args.noise)
    except ValueError as e:
        return _fail(str(e))
    print(_heading(args, track))
    for line in res.lines():
        print(line)
    failed = _write_plot(args, res, f"{shown(args.track)} against {shown(args.scene)}")
    if failed is not None:
        return failed
    if args.plot:
        print(f"wrote {shown(args.plot)}")
    return EXIT_OK if res.covered else EXIT_STOPPED


def _fit(args) -> int:
    from .fitting import fit, parse_bounds

    loaded = _measured(args, [args.out, args.plot])
    if isinstance(loaded, int):
        return loaded
    scene, track = loaded
    keys = [key.strip() for key in args.fit.split(",")]
    try:
        bounds = dict(parse_bounds(text) for text in args.bounds)
        result = fit(scene, track, keys, bounds=bounds, loss=args.loss, point=args.point, noise=args.noise)
    except ValueError as e:   # FitError, SceneError
        return _fail(shown(str(e)))
    print(_heading(args, track))
    for line in result.lines():
        print(line)
    files = {}
    if args.out:
        files[args.out] = result.scene.dumps()
    if args.plot:
        from .residual_plot import figure_png

        files[args.plot] = figure_png(result.residuals, f"{shown(args.track)} against {shown(args.scene)} "
                                                        f"fitted ({', '.join(keys)})")
        if files[args.plot] is None:
            return _fail("cannot draw the residuals: matplotlib is not installed; nothing was written")
    if files:
        folder = Path(next(iter(files))).parent
        try:  # the fitted scene and its residuals: both replaced, or neither
            replace_together(folder, {Path(path).name: content for path, content in files.items()},
                             keep=[scene_path(args.scene), track_path(args.track)], kept_name=FIT_KEPT_NAME)
        except OSError as e:
            return _fail(f"cannot write {shown(e.filename or folder)}: {e.strerror or e}")
        print(f"wrote {', '.join(shown(path) for path in files)}")
    return EXIT_OK if result.converged else EXIT_STOPPED


def _compiles(scene) -> str | None:
    """None when the scene's landscape compiles, else why not (one line): before any run."""
    from .landscape import landscape_of

    try:
        landscape_of(scene).compiled
    except ValueError as e:  # FormulaError
        return str(e)
    return None


def _examples() -> int:
    examples = example_descriptions()
    width = max(len(name) for name, _ in examples)
    for name, description in examples:
        print(f"{name:<{width}}  {shown(description)}")
    print(f"\nRun one by name (rollball simulate hills); the files are in {EXAMPLES_DIR}")
    return EXIT_OK


def _bench(args) -> int:
    from . import bench

    def log(text: str) -> None:
        print(text, file=sys.stderr)

    try:
        print(bench.run(Path(args.out), bench.QUICK if args.quick else bench.FULL, log=log))
    except OSError as e:
        return _fail(f"cannot write to {shown(e.filename or args.out)}: {e.strerror or e}")
    return EXIT_OK


def _fail(message: str) -> int:
    print(f"rollball: error: {message}", file=sys.stderr)
    return EXIT_BAD_INPUT


def _warning(message, category, filename, lineno, file=None, line=None):
    """A warning as one line of its own (the summary stays one line)."""
    print(f"rollball: warning: {' '.join(str(message).split())}", file=sys.stderr)


COMMANDS = {"simulate": _simulate, "compare": _compare, "sweep": _sweep, "check": _check, "fit": _fit,
            "examples": lambda args: _examples(), "bench": _bench}
INTERRUPTED = {"simulate": "rollball: interrupted", "compare": "rollball: interrupted (nothing written)",
               "check": "rollball: interrupted", "fit": "rollball: interrupted (nothing written)"}


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command not in COMMANDS:
        parser.print_help()
        return EXIT_BAD_INPUT
    with warnings.catch_warnings():
        warnings.showwarning = _warning
        # overflowing or undefined numbers in derived columns are reported by the run's status
        warnings.filterwarnings("ignore", category=RuntimeWarning)
        try:
            code = COMMANDS[args.command](args)
            sys.stdout.flush()
        except KeyboardInterrupt:
            if args.command not in INTERRUPTED:
                raise
            print(INTERRUPTED[args.command], file=sys.stderr)
            return 130
        except BrokenPipeError:  # the reader left (| head): stop quietly, as SIGPIPE would
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return EXIT_BROKEN_PIPE
    return code

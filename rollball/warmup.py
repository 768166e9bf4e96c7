"""Compiling the integrator before it is needed.

The stepping kernel is made into machine code the first time a run needs it: from the code
RollBall ships, in about two seconds; where that does not fit the machine, numba compiles
it, which takes a minute or more (machine_code.py). Either machine code is kept in the cache
folder, so later processes load it in well under a second. ``warm_up`` runs every method once on a tiny run,
and a tiny sweep, so that this happens now; ``python -m rollball.warmup`` does it with
progress on stderr (the setup script calls it). ``compile_notice`` tells a caller when the
kernel starts being compiled.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import time
from contextlib import ExitStack, contextmanager

from . import machine_code
from .examples import DEFAULT_EXAMPLE
from .scene import Scene
from .simulation import simulate
from .sweeps import sweep
from .tableaus import METHODS


def variants() -> list[tuple[str, bool]]:
    """Every (method, munthe_kaas) the kernel runs: each method, and the classic update too
    where the method allows it. Methods sharing compiled code cost nothing after the first."""
    return [(name, mk) for name, method in METHODS.items()
            for mk in ((True, False) if method.classic_allowed else (True,))]


def warm_up(progress=None, first=(), ready=None) -> None:
    """Compile (or load from the cache folder) the kernel for every method, the variants in
    ``first`` (``(method, munthe_kaas)`` pairs) before the others. ``progress(done, total,
    text)`` is called before each part, ``ready(method, munthe_kaas)`` after it."""
    scene = Scene.load(DEFAULT_EXAMPLE)
    todo = [v for v in first if v in variants()] + [v for v in variants() if v not in first]
    total = len(todo) + 1
    for done, (method, mk) in enumerate(todo):
        if progress:
            progress(done, total, f"{method}{'' if mk else ' classic'}")
        simulate(scene, method=method, munthe_kaas=mk, t_end=0.01)
        if ready:
            ready(method, mk)
    if progress:
        progress(len(todo), total, "sweeps")
    sweep(dataclasses.replace(scene, duration=0.01), {"start.vx": [scene.start.vx]}, workers=1)
    if progress:
        progress(total, total, "done")


class _FirstCompile:
    def __init__(self, say):
        self.say, self.said = say, False

    def __call__(self):   # machine_code makes the kernel's machine code, or numba compiles it
        if not self.said:
            self.said = True
            self.say()



def _numba_listener(first: _FirstCompile):
    """A listener to numba's compile events that calls ``first`` when numba compiles a function
    of RollBall's (not a landscape's callback)."""
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev):
            module = getattr(ev.data["dispatcher"].py_func, "__module__", "") or ""
            if module.split(".")[0] == "rollball":
                first()

        def on_end(self, ev):
            pass

    return event.install_listener("numba:compile", Listener())


@contextmanager
def compile_notice(say):
    """Within the block, call ``say()`` once when RollBall's kernel starts being compiled: its
    shipped code made into machine code for this processor, or numba compiling part of it
    (nothing is said when it comes from the cache folder)."""
    first = _FirstCompile(say)
    machine_code.listeners.append(first)
    try:
        with ExitStack() as stack:
            if "numba" in sys.modules:   # (else numba is imported only by machine_code, which says so)
                stack.enter_context(_numba_listener(first))
            yield
    finally:
        machine_code.listeners.remove(first)


def main(argv: list[str] | None = None) -> int:
    """``python -m rollball.warmup [RUNS]``: warm up, the runs named (e.g. ``rk4/classic``)
    first; say on stderr what is compiled (nothing but a last line when it is cached) and on
    stdout ``ready METHOD mk|classic`` as each variant becomes ready."""
    from .run_specs import parse_runs

    args = sys.argv[1:] if argv is None else argv
    try:
        first = [(spec.method, spec.munthe_kaas) for spec in parse_runs(args[0])] if args else []
    except ValueError as error:
        print(f"rollball: {error}", file=sys.stderr)
        return 2
    started = time.perf_counter()
    compiling, current = False, ""

    def say():
        nonlocal compiling
        compiling = True
        print("rollball: compiling the integrator (first time only; kept on disk) ...", file=sys.stderr)
        print(f"  {current}", file=sys.stderr, flush=True)

    def progress(done, total, text):
        nonlocal current
        current = f"[{done + 1}/{total}] {text}"
        if compiling and done < total:
            print(f"  {current}", file=sys.stderr, flush=True)

    def ready(method, mk):
        print(f"ready {method} {'mk' if mk else 'classic'}", flush=True)

    try:
        with compile_notice(say):
            warm_up(progress, first, ready)
    except BrokenPipeError:   # whoever reads the "ready" lines (the app) has gone: so do we
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())   # no complaint at exit
        return 1
    print(f"rollball: the integrator is ready ({time.perf_counter() - started:.1f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

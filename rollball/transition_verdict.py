"""What the check of a run's transitions found (``transition_check.check_transitions``): each
transition taken again (``Retake``) with its verdict, the whole check (``TransitionCheck``) and
the warning it gives. Data and sentences only: ``trajectory`` holds a check without the means
to make one."""

from __future__ import annotations

from dataclasses import dataclass

TIGHTER = 100.0        # adaptive: taken again with tolerances 100 and 10^4 times tighter...

CONVERGED, NEGLIGIBLE, PLATEAU, GROWS, CHANGED = "converged", "negligible", "plateau", "grows", "changed"
LOOSE = "loose"


@dataclass(frozen=True)
class Retake:
    """One transition of the run taken again: its ``kind`` and ``time`` (s) in the run (its
    position ``index`` in ``Trajectory.transitions``), from the row at ``start`` (s), with each
    of ``steps`` (fixed: dt, dt/2, dt/4; adaptive: the run's own rtol, then 100 and 10^4 times
    tighter), the transition's time in each (``times``; None where that retake had no such
    transition there: ``found`` says what it had instead) and the ``verdict`` (CONVERGED;
    NEGLIGIBLE: every move below the floor, MOVE_FLOOR or, adaptive, what the tolerance allows;
    PLATEAU: the moves shrink more slowly than the method's order says; GROWS: a finer retake
    moves it more; CHANGED: the kinds differ; LOOSE, adaptive: the first move, the run's own error
    as the tighter retakes tell it, is above ``allowed``, a time its tolerance does not allow)."""

    index: int
    kind: str
    time: float
    start: float
    steps: tuple[float, ...]
    times: tuple[float | None, ...]
    found: tuple[str, ...]
    verdict: str
    allowed: float = float("inf")   # s: the first move above this is LOOSE (adaptive; fixed steps: inf)

    @property
    def converged(self) -> bool:
        return self.verdict in (CONVERGED, NEGLIGIBLE)

    @property
    def moves(self) -> tuple[float, ...]:
        """|t_{k+1} − t_k| between successive retakes (empty where one lacks the transition)."""
        if None in self.times:
            return ()
        return tuple(abs(b - a) for a, b in zip(self.times, self.times[1:]))


@dataclass(frozen=True)
class TransitionCheck:
    """The check of a finished run's transitions (``check_transitions``): the ``method``, its
    ``order`` and whether it is ``adaptive``; the transitions taken again (``retakes``, at most
    MAX_CHECKED), how many kernel-located ones were not: ``unchecked`` beyond the cap, ``skipped``
    with no row to start from (a change at the run's start, or one too far after its row) or
    whose retake failed; and ``invented``: sentences on transitions the sequence itself shows the
    motion does not have (two at one instant or out of order; a slip turning about where the
    slip had not stopped)."""

    method: str
    order: int
    adaptive: bool
    retakes: tuple[Retake, ...] = ()
    unchecked: int = 0
    invented: tuple[str, ...] = ()
    skipped: int = 0

    @property
    def converged(self) -> bool:
        return not self.invented and all(retake.converged for retake in self.retakes)

    @property
    def failed(self) -> tuple[Retake, ...]:
        return tuple(retake for retake in self.retakes if not retake.converged)

    def warning(self) -> str | None:
        """The sentence ``Trajectory.warnings()`` shows (None where every transition converged): the
        first transition that did not (and which others did not), the first invented one (and how
        many more), and what to do."""
        if self.converged:
            return None
        parts = []
        failed = self.failed
        if failed:
            others = " and ".join(f"the {NAMES.get(r.kind, r.kind)} at {r.time:.6g} s" for r in failed[1:])
            nor = f" (nor {'are' if len(failed) > 2 else 'is'} {others})" if others else ""
            parts.append(_sentence(failed[0], self) + ": not converged" + nor)
        if self.invented:
            more = len(self.invented) - 1
            parts.append(self.invented[0] + ": a change the motion does not have"
                         + (f" ({more} more like it)" if more else ""))
        advice = "try tighter tolerances" if self.adaptive else "try a smaller step or dopri5"
        if self.unchecked:
            n = len(self.retakes)
            advice += f" (only the first {n} transition{' was' if n == 1 else 's were'} taken again)"
        return "; ".join(parts + [advice])


NAMES = {"liftoff": "lift-off"}   # (as ``Transition.sentence`` writes it)


def _sentence(retake: Retake, check: TransitionCheck) -> str:
    what = f"the {NAMES.get(retake.kind, retake.kind)} at {retake.time:.6g} s"
    if check.adaptive:
        levels = ["with its tolerances", f"with tolerances {TIGHTER:g} times tighter",
                  f"with tolerances {TIGHTER ** 2:g} times tighter"]
        expected = f"{check.method} should move it by about 1/{TIGHTER:g} as much each time"
    else:
        levels = [f"at dt {retake.steps[0]:g}", "when the step was halved", "when it was halved again"]
        expected = f"{check.method} should move it by about 1/{2 ** check.order} as much each time"
    if retake.verdict == CHANGED:
        k = next(i for i, t in enumerate(retake.times) if t is None)
        return (f"{what} is not there {levels[k]} (taken again from t = {retake.start:.6g} s: "
                f"{retake.found[k]})")
    moves = retake.moves
    if retake.verdict == LOOSE:
        expected = f"more than rtol {retake.steps[0]:.0e} allows: about {retake.allowed:.2g} s at most"
    return (f"{what} moved by {moves[0]:.2g} s {levels[1]} and by {moves[1]:.2g} s {levels[2]} "
            f"({expected})")

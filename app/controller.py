"""The run controller: one or several runs of a scene, computed in a worker thread and played
back in sync on one clock. A QObject without widgets, so it is tested without a window or GL.

States: ``ready`` (nothing started), ``running`` (playing; the worker may still be computing:
see ``computed``, and before that compiling a method's kernel: see ``compiling``), ``paused``, ``finished`` (played to
the end), ``stopped`` (the user stopped it; what was computed stays). Signals tell the window what to show:

- ``stateChanged(state)`` whenever the state or ``computed`` changes,
- ``frameReady(force)`` when the play time moved (``force``: draw even an unchanged row),
- ``event(run, kind, t)`` when playback passes something worth saying (``"liftoff"`` where a
  glued ball would leave the surface; a transition of the contact: ``"slip"``, ``"grip"``,
  ``"liftoff"`` or ``"landing"``, its kind as in ``Run.transitions``),
- ``finished()`` when playback reached the end of every run,
- ``failed(message)`` when the core raised in the worker,
- ``measured()`` when a comparison's reference is known and every run's true error against
  it (``Run.errors``) has been computed.
"""

from __future__ import annotations

import math
import time
from functools import partial

from PySide6 import QtCore

from rollball import Scene, Simulation, Trajectory

from .playback import RunBuffer
from .worker import COMPILING, Worker, reference_worker, stream_worker

READY, RUNNING, PAUSED, FINISHED, STOPPED = "ready", "running", "paused", "finished", "stopped"
FRAME_MS = 16              # advance the clock and redraw at most ~60 Hz
STEP_SPEED = 10.0          # simulated seconds per second a Step frame assumes at "as fast as computed"


class Run:
    """One simulation and the rows the GUI thread has received of it."""

    def __init__(self, simulation: Simulation, landscape, label: str = "", color: str | None = None):
        scene = simulation.scene
        self.simulation = simulation
        self.label, self.color = label, color
        self.seconds = 0.0                 # compute time, known once the worker is done with it
        self.errors: dict | None = None    # true errors against the reference, per row
        modes = (lambda: simulation.modes) if hasattr(type(simulation), "modes") else None
        self.buffer = RunBuffer(landscape, scene.ball.mass, scene.ball.radius, scene.gravity,
                                capacity=simulation.row_capacity, modes=modes)
        self.liftoff_announced = False
        self.announced = 0                 # transitions announced so far
        self.ended = False                 # the run's computation has ended and all its rows are here

    def index_at(self, t: float) -> int:
        return self.buffer.index_at(t)

    @property
    def transitions(self) -> list:
        """The changes of the contact's mode found so far (``trajectory.Transition``s, in time
        order; none in the 2011 model)."""
        return list(getattr(self.simulation, "transitions", ()))

    @property
    def glued(self) -> bool:
        """The ball stays on the surface after a lift-off (the 2011 behaviour): a lift-off is
        reported, not flown."""
        return self.simulation.scene.contact.after_liftoff == "glued"

    def trajectory(self) -> Trajectory:
        """The rows received so far as a trajectory (no copy), with the finished run's check of
        its transitions (what ``warnings`` says of them); ``modes`` None where the run cannot
        change mode (the 2011 model), as ``Simulation.trajectory`` gives it."""
        scene = self.simulation.scene
        modes = self.buffer.mode if getattr(self.simulation, "segmented", True) else None
        return Trajectory(self.buffer.rows, mass=scene.ball.mass, radius=scene.ball.radius,
                          gravity=scene.gravity, modes=modes, transitions=tuple(self.transitions),
                          transition_check=getattr(self.simulation, "transition_check", None))


class RunController(QtCore.QObject):
    stateChanged = QtCore.Signal(str)
    frameReady = QtCore.Signal(bool)
    event = QtCore.Signal(int, str, float)
    finished = QtCore.Signal()
    failed = QtCore.Signal(str)
    measured = QtCore.Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.runs: list[Run] = []
        self.thread: Worker | None = None   # computing the runs
        self._seconds: list[float] = []    # its processor time in each run so far
        self.state = READY
        self.computed = False          # the worker has finished every run
        self.compiling = False         # the worker is compiling a kernel (no rows yet)
        self.play_time = 0.0
        self.speed = 1.0               # simulated seconds per wall-clock second (inf: as computed)
        self.reference: tuple[Trajectory, float] | None = None   # trajectory, its error estimate
        self._reference_thread: Worker | None = None
        self._last_tick = self._frame_started = time.perf_counter()
        self.timer = QtCore.QTimer(self, interval=FRAME_MS, timerType=QtCore.Qt.TimerType.PreciseTimer)
        self.timer.timeout.connect(self._tick)

    # -- what there is ---------------------------------------------------------------

    @property
    def simulation(self) -> Simulation | None:
        """The first run's simulation (the only one outside compare mode)."""
        return self.runs[0].simulation if self.runs else None

    @property
    def buffer(self) -> RunBuffer | None:
        return self.runs[0].buffer if self.runs else None

    @property
    def t_end(self) -> float:
        return max((run.simulation.t_end for run in self.runs), default=0.0)

    @property
    def end_time(self) -> float:
        """How far playback may go: every run has rows up to here (or has ended before it)."""
        ends = [run.buffer.end_time for run in self.runs]
        if not ends:
            return 0.0
        if self.computed:
            return max(ends)
        going = [run.buffer.end_time for run in self.runs if not run.ended]
        return min(going) if going else max(ends)

    # -- commands --------------------------------------------------------------------

    def start(self, runs: list[Run], reference: tuple[Scene, float, float] | None = None,
              warm_ups: list[Simulation] = ()) -> None:
        """Compute and play these runs from t = 0 (whatever ran before is dropped). With
        ``reference`` = (scene, t_end, record_dt) a reference run is computed alongside and
        every run is measured against it; ``warm_ups`` run first, so compiling is not timed."""
        self.reset()
        self.runs = list(runs)
        if reference is not None:
            self._start_reference(*reference)
        runs = self.runs
        self._seconds = [0.0] * len(runs)
        self.thread = worker = stream_worker([run.simulation for run in runs], [run.buffer.derive for run in runs],
                                             warm_ups, self._seconds)
        # each signal names its worker: what a worker stopped meanwhile still says is dropped
        worker.progressed.connect(partial(self._progress, worker))
        worker.failed.connect(self.failed)
        worker.ended.connect(partial(self._computed, worker))
        self._set_state(RUNNING)
        self._last_tick = time.perf_counter()
        self.thread.start()
        self.timer.start()

    def toggle_pause(self) -> None:
        if self.state == RUNNING:
            self._set_state(PAUSED)
        elif self.state == PAUSED:
            self._last_tick = time.perf_counter()
            self.timer.start()   # stopped if the run had played to its end before a seek
            self._set_state(RUNNING)

    def pause(self) -> None:
        if self.state == RUNNING:
            self._set_state(PAUSED)

    def step(self, frames: int = 1) -> None:
        """Pause and move the clock by ``frames`` frames (back if negative) at the playback speed."""
        if self.state not in (RUNNING, PAUSED, FINISHED):
            return
        speed = self.speed if math.isfinite(self.speed) else STEP_SPEED
        self.seek(self.play_time + frames * FRAME_MS / 1000 * speed)
        self.pause()

    def seek(self, t: float) -> None:
        """Show time t (held within what is computed). A finished run pauses there, so Resume
        plays on from that moment; a running one plays on from it."""
        if not self.runs:
            return
        self.play_time = min(max(0.0, t), self.end_time)
        self._last_tick = time.perf_counter()
        if self.state == FINISHED:
            self._set_state(PAUSED)
        self._frame(force=True)

    def stop(self) -> None:
        """Stop computing and playing; what was computed stays."""
        if self.state not in (RUNNING, PAUSED):
            return
        self._stop_worker()
        self.timer.stop()
        self._set_state(STOPPED)
        self._frame(force=True)
        self._measure()

    def reset(self) -> None:
        """Drop the runs: back to ready at t = 0."""
        self._stop_worker()
        if self._reference_thread is not None:
            self._reference_thread.cancel(wait=False)   # ends within a chunk; its result is not wanted
        self.timer.stop()
        self.runs, self.computed, self.compiling, self.play_time = [], False, False, 0.0
        self.reference, self._reference_thread = None, None
        self._set_state(READY)

    def shutdown(self) -> None:
        """Reset (before the app quits): the runs and the reference are cancelled."""
        self.reset()

    # -- the worker ------------------------------------------------------------------

    def _stop_worker(self) -> None:
        if self.thread is not None:
            self.thread.cancel()   # within a chunk (bounded); its late signals are dropped
            self._take_seconds()
            self.thread = None

    def _progress(self, worker: Worker, message: tuple) -> None:
        if worker is not self.thread:
            return   # said before its worker was stopped: its runs were dropped
        if message[0] == COMPILING:
            self._set_compiling(True)
            return
        _rows, index, block, ended = message   # worker.ROWS
        run = self.runs[index]
        if block is not None:
            run.buffer.append(block)
        run.ended = ended
        self._set_compiling(False)

    def _set_compiling(self, on: bool) -> None:
        if on != self.compiling:
            self.compiling = on
            self.stateChanged.emit(self.state)

    def _take_seconds(self) -> None:
        for run, seconds in zip(self.runs, self._seconds):
            run.seconds = seconds

    def _computed(self, worker: Worker) -> None:
        if worker is not self.thread:
            return   # a worker stopped meanwhile
        self.computed, self.compiling = True, False
        self._take_seconds()
        self.thread = None
        self.stateChanged.emit(self.state)
        self._measure()

    # -- the reference ---------------------------------------------------------------

    def _start_reference(self, scene: Scene, t_end: float, record_dt: float) -> None:
        thread = self._reference_thread = reference_worker(scene, t_end, record_dt)
        thread.done.connect(lambda result: self._reference_done(thread, *result))
        thread.failed.connect(lambda message: thread is self._reference_thread and self.failed.emit(
            f"The reference run failed: {message}"))
        thread.start()

    def _reference_done(self, thread, trajectory: Trajectory, estimate: float) -> None:
        if thread is not self._reference_thread:
            return  # a reference of runs since dropped
        self.reference = (trajectory, estimate)
        self._measure()

    def _measure(self) -> None:
        """Every run's errors against the reference, once both are complete (or the runs were
        stopped: then up to where they got)."""
        if self.reference is None or self.thread is not None or not self.runs:
            return
        from rollball.comparison import error_series

        for run in self.runs:
            run.errors = error_series(run.trajectory(), self.reference[0])
        self.measured.emit()

    # -- the clock -------------------------------------------------------------------

    def _tick(self) -> None:
        now = time.perf_counter()
        elapsed, self._last_tick = now - self._last_tick, now
        self._frame_started = now
        QtCore.QTimer.singleShot(0, self, self._frame_done)  # once this frame is painted; never after self is deleted
        if not self.runs or self.state != RUNNING:
            return  # paused: nothing moves (Step draws its own frame)
        end = self.end_time
        self.play_time = end if math.isinf(self.speed) else min(self.play_time + elapsed * self.speed, end)
        if self.computed and self.play_time >= end:
            self.play_time = end
            self.timer.stop()
            self._set_state(FINISHED)
            self._frame(force=True)
            self.finished.emit()
        else:
            self._frame(force=False)

    def _frame_done(self) -> None:
        """Pace the frames: wait at least as long as the last one took to draw and show, so the
        event loop keeps half its time for input even where OpenGL is rendered in software."""
        cost = time.perf_counter() - self._frame_started
        self.timer.setInterval(max(FRAME_MS, round(1000 * cost)))

    def _frame(self, force: bool) -> None:
        self.frameReady.emit(force)
        for i, run in enumerate(self.runs):
            if not len(run.buffer):
                continue
            shown = run.buffer.t[run.index_at(self.play_time)]
            liftoff = run.simulation.liftoff_time  # set by the kernel as soon as it happens
            if run.glued and liftoff is not None and not run.liftoff_announced and shown >= liftoff:
                run.liftoff_announced = True
                self.event.emit(i, "liftoff", liftoff)
            changes = run.transitions
            while run.announced < len(changes) and changes[run.announced].time <= shown:
                change = changes[run.announced]
                run.announced += 1
                self.event.emit(i, change.kind, change.time)

    def _set_state(self, state: str) -> None:
        self.state = state
        self.stateChanged.emit(state)


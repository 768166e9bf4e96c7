"""The window's run commands: Start (waiting for the integrator's warm-up when it must), Pause,
Step, Stop, Reset, seeking and lift-off, what is said when a run ends or passes an event, and
which run controls are enabled in which state.

The runs themselves (computing, the playback clock) live in the window's ``RunController``;
drawing a moment of them is ``drawing.Drawing``'s; compare mode's runs are made by
``compare_mode.CompareMode``. The window wires its actions to these methods.
"""

from __future__ import annotations

from PySide6 import QtCore

from rollball import Scene, Simulation, Status
from rollball.simulation import recording

from . import contact_view
from .controller import FINISHED, PAUSED, READY, RUNNING, STOPPED, Run
from .session import run_spec
from .timeline import Marker
from .warmup import WarmUp

LIFTOFF_COLOR, STOP_COLOR = contact_view.KIND_COLORS["liftoff"], "#c0392b"   # markers on the time slider
START_WORDS = {READY: ("Start", "Start the run from t = 0"),                # what Start does, by state
               PAUSED: ("Resume", "Resume playback from where it was paused"),
               FINISHED: ("Restart", "Run again from t = 0"),
               STOPPED: ("Restart", "Run again from t = 0")}
STATE_WORDS = {READY: "Ready", RUNNING: "Running", PAUSED: "Paused", FINISHED: "Finished", STOPPED: "Stopped"}


class RunCommands:
    """The run commands of ``window`` (a ``MainWindow``: its controller, panel, actions, view and
    status bar)."""

    def __init__(self, window):
        self.window = window
        self.controller = window.controller
        self.warmup = WarmUp(window)          # compiling the integrator in the background
        self.warmup.readied.connect(self._warmed)
        self.warmup.ended.connect(self._warmed)
        self.start_waiting = False            # Start was pressed meanwhile

    @property
    def state(self) -> str:
        return self.controller.state

    # -- the integrator's warm-up ----------------------------------------------------

    @property
    def preparing(self) -> QtCore.QProcess | None:
        """The integrator's warm-up process while it runs."""
        return self.warmup.process

    def prepare_integrator(self, command: list[str] | None = None) -> None:
        """Compile the integrator for every method in a process of its own, from launch, the
        current scene's method first (``WarmUp``). A Start meanwhile waits until its method is
        ready, saying so with a busy indicator, and the run starts by itself."""
        scene = self.window.scene
        self.warmup.start(command or WarmUp.command(None if scene is None else run_spec(scene)))

    def _must_wait(self) -> bool:
        """Whether a Start now would compile what the warm-up is compiling."""
        scene = self.window.scene
        return self.warmup.must_wait(None if self.window.compare.active or scene is None else run_spec(scene))

    def stop_preparing(self) -> None:
        self.warmup.stop()

    def _warmed(self) -> None:
        """A variant is ready (or the warm-up has ended): a start waiting for it goes."""
        if self.warmup.process is None:
            self.window.progress.setRange(0, 1000)
        if self.start_waiting and not self._must_wait():
            self.start_waiting = False
            self.start()

    # -- commands --------------------------------------------------------------------

    def start(self) -> None:
        """Start from t = 0 (or resume when paused)."""
        w = self.window
        if self.state == PAUSED:
            self.toggle_pause()
            return
        if self._must_wait():
            self.start_waiting = True
            w.progress.setRange(0, 0)   # busy
            w.show_message("Preparing the integrator (first run only)… the run starts by itself "
                           "when it is ready")
            self.update_controls()
            return
        w.panel.apply()
        scene = w.scene
        if scene is None:
            w._warn("Cannot start", f"There is no valid scene to run: {w.panel.error_text}")
            return
        stale = w.panel.error_text  # the fields as typed do not make a scene: say what runs
        self.reset()
        if w.compare.active:
            try:
                w.compare.start(scene)
            except ValueError as error:
                w._warn("Cannot compare", str(error))
            w.drawing.follow(w.follow_action.isChecked())
            return
        try:
            simulation = Simulation(scene, **recording(scene, record_every=w.panel.record_every.value()))
        except Exception as error:  # every refusal is said, whatever raised it
            w._warn("Cannot start", str(error) if isinstance(error, ValueError)
                    else f"{type(error).__name__}: {error}")
            return
        if simulation.adaptive:
            note = f"Running adaptive steps to t = {scene.duration:g} s"
        else:
            every = simulation.record_every
            note = (f"Running to t = {scene.duration:g} s in steps of {simulation.dt:g} s"
                    + (f" (recording every {every}th step)" if every > 1 else ""))
        w.plots.set_duration(scene.duration)
        w.timeline.set_span(simulation.t_end)
        self.controller.start([Run(simulation, w.landscape)])
        w.show_message(note + (f" of the last valid scene (not the fields: {stale})" if stale else ""),
                       warning=bool(stale))

    def load_run(self, result) -> None:
        """Run the scene with a comparison run's method and step (or tolerance): Speed against
        Error's click."""
        w = self.window
        data = w.scene.to_dict()
        integrator = data["integrator"]
        integrator.update(method=result.spec.method, munthe_kaas=result.spec.munthe_kaas)
        if result.dt is not None:
            integrator["dt"] = result.dt
        else:
            integrator.update(rtol=result.rtol, atol=result.atol)
        scene = Scene.from_dict(data)
        w.compare_action.setChecked(False)
        w.session.load(w.scene, scene, "Load Run from Speed against Error")
        self.start()
        w.activateWindow()

    def toggle_pause(self) -> None:
        self.controller.toggle_pause()

    def step_frame(self) -> None:
        """Advance the playback by one frame (starting the run paused if needed)."""
        if self.state == READY:
            self.start()
            self.controller.pause()
            return
        self.controller.step()

    def stop(self) -> None:
        """Stop computing and playing; what was computed stays (export it, or Reset)."""
        if self.state not in (RUNNING, PAUSED):
            return
        self.controller.stop()
        t, liftoff = self.controller.play_time, self.controller.simulation.liftoff_time
        self.window.show_message(f"Stopped at t = {t:.4g} s"
                                 + (self._liftoff_note() if liftoff is not None and liftoff <= t else "")
                                 + " (what was computed can be exported)")

    def reset(self) -> None:
        """Back to the start of the current scene; the computed run is dropped."""
        w = self.window
        self.start_waiting = False
        w.progress.setRange(0, 1000)
        self.controller.reset()
        w.compare.clear()   # no results of runs that are gone
        w.drawing.clear()

    # -- the time shown --------------------------------------------------------------

    def seek(self, t: float) -> None:
        """Show the moment t of the computed run (held within what is computed)."""
        self.controller.seek(t)

    def liftoff_time(self) -> float | None:
        simulation = self.controller.simulation
        return simulation.liftoff_time if simulation is not None else None

    def go_to_liftoff(self) -> None:
        t = self.liftoff_time()
        if t is not None:
            self.seek(t)

    def show_events(self) -> None:
        """Lift-off (of a glued ball), every run's transitions of the contact (slip, grip,
        lift-off, landing; in compare mode named by run) and an early stop as markers on the
        time slider and links beside it."""
        w, simulation = self.window, self.controller.simulation
        events = []
        first = self.controller.runs[0]
        if simulation.liftoff_time is not None and first.glued:
            events.append(Marker(simulation.liftoff_time, LIFTOFF_COLOR,
                                 f"lift-off at t = {simulation.liftoff_time:.4g} s", kind="lift-off"))
        compare = w.compare.active
        for run in self.controller.runs if compare else self.controller.runs[:1]:
            events += contact_view.markers(run.transitions, run.label if compare else "")
        events.sort(key=lambda marker: marker.time)
        if simulation.status not in (None, Status.OK, Status.ABORTED) and len(self.controller.buffer):
            t = self.controller.buffer.end_time
            events.append(Marker(t, STOP_COLOR, f"{simulation.status.value.replace('_', ' ')} at t = {t:.4g} s",
                                 kind="stop"))
        if events != w.timeline.markers:
            w.timeline.set_markers(events)
            w.liftoff_action.setEnabled(simulation.liftoff_time is not None)

    # -- what the controller says ----------------------------------------------------

    def state_changed(self, state: str) -> None:
        self.update_controls()
        if state != READY:
            self.window.start_editing.hide()   # a run is shown: no preview, no handles
        if state == PAUSED:
            self.window.drawing.plot()   # the plots catch up with the ball where it stopped

    def finished(self) -> None:
        w = self.window
        if w.compare.active:
            w.compare.finished()
            return
        simulation = self.controller.simulation
        status, text = simulation.status, simulation.message()
        liftoff = self._liftoff_note()   # every event of the run stays in its last word
        if status is Status.OK:
            warnings = "".join(f"; {note}" for note in self.controller.runs[0].trajectory().warnings())
            glued_liftoff = self.controller.runs[0].glued and simulation.liftoff_time is not None
            w.show_message(f"Finished: {text}" + liftoff + warnings, warning=bool(warnings or glued_liftoff))
        else:
            w.show_message(f"Stopped early ({status.value.replace('_', ' ')}): {text}" + liftoff, warning=True)

    def _liftoff_note(self) -> str:
        run = self.controller.runs[0]
        if not run.glued:
            changes = run.transitions
            if run.simulation.scene.stop_at_rest and changes and changes[-1].kind == "rest":
                changes = changes[:-1]   # the run ended there: its message says where and when
            return contact_view.summary(changes)
        t = self.controller.simulation.liftoff_time
        return "" if t is None else f"; lift-off at t = {t:.4g} s (not physical from there on)"

    def run_event(self, index: int, kind: str, t: float) -> None:
        """Playback has passed an event: the status bar says so (the view marks it: ``Drawing``)."""
        w = self.window
        run = self.controller.runs[index]
        who = f"{run.label}: " if w.compare.active else ""
        if kind == "liftoff" and run.glued:
            w.show_message(f"{who}Lift-off at t = {t:.4g} s: the real ball would leave the surface "
                           f"here; the model keeps it on, so what follows is not physical", warning=True)
            return
        w.show_message(contact_view.sentence(kind, t, who))

    def update_controls(self) -> None:
        """The run controls as the state says: what Start does, which commands are open."""
        w, controller = self.window, self.controller
        state, computed = self.state, controller.computed
        text, tip = START_WORDS.get(state, START_WORDS[READY])
        w.start_action.setEnabled(state != RUNNING)
        w.start_action.setText(text)
        w.start_action.setStatusTip(tip)
        w.start_action.setToolTip(f"{tip} ({w.start_action.shortcut().toString()})")
        w.pause_action.setEnabled(state in (RUNNING, PAUSED))
        w.pause_action.setChecked(state == PAUSED)
        w.step_action.setEnabled(state in (READY, PAUSED, RUNNING))
        w.stop_action.setEnabled(state in (RUNNING, PAUSED))
        w.reset_action.setEnabled(state != READY)
        w.export_action.setEnabled((computed or state == STOPPED) and controller.simulation is not None)
        w.animation_action.setEnabled(bool(controller.runs))
        w.revert_action.setEnabled(w.files.dirty)
        for action in (w.back_action, w.forward_action, w.first_action, w.last_action):
            action.setEnabled(bool(controller.runs))
        w.liftoff_action.setEnabled(self.liftoff_time() is not None)
        if controller.runs:
            w.timeline.set_available(controller.end_time)
            self.show_events()
        doing = "compiling…" if controller.compiling else "computing…"
        w.state_label.setText("Preparing…" if self.start_waiting
                              else STATE_WORDS[state] if computed or state in (READY, STOPPED, FINISHED)
                              else f"{STATE_WORDS[state]} ({doing})")

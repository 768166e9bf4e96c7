"""The main window: inputs around the 3-D view, run controls, readouts, plots, files."""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from rollball import Scene, SceneError, Simulation, Status, Trajectory, __version__
from rollball.examples import example_scenes
from rollball.files import atomic_write_bytes
from rollball.geometry import unit_normal
from rollball.landscape import landscape_for
from rollball.simulation import recording
from rollball.trajectory import CENTER, R, T

from .controller import FINISHED, PAUSED, READY, RUNNING, STOPPED, Run, RunController
from .document import Document
from .inputs import ScenePanel
from .plots import LivePlots
from .preferences import Preferences
from .readouts import Readouts
from .view3d import SceneView

PLOT_EVERY = 12                # plots every 12th frame (~5 Hz): redrawing their axes is costly
SPEEDS = (("0.1×", 0.1), ("0.25×", 0.25), ("0.5×", 0.5), ("Real time", 1.0), ("2×", 2.0),
          ("5×", 5.0), ("10×", 10.0), ("As fast as computed", math.inf))
SCENE_FILTER = "RollBall scenes (*.json);;All files (*)"
CSV_FILTER = "CSV files (*.csv);;All files (*)"

LIMITS_TEXT = """<p><b>What the model assumes.</b> A homogeneous solid ball rolls without slipping
and always touches the surface in exactly one point.</p>
<p><b>Lift-off.</b> Where the normal force F·N drops to zero the real ball would leave the
surface (over a crest, at high speed). The model keeps it glued on, so from there on the
motion is not physical. The app marks the first lift-off point in orange and says so in the
status bar; the run goes on so you can see what the equations do.</p>
<p><b>Does not fit.</b> Where the surface curves up more tightly than the ball (r·κ ≥ 1 for a
principal curvature κ of a valley) the ball cannot touch in one point. These regions are
drawn in red; a run that reaches one stops there with the time and position.</p>
<p><b>Non-finite.</b> A landscape that cannot be evaluated where the ball is (log or sqrt
outside its domain, a pole), or a step so large that the numbers overflow, stops the run with
the time and position. Undefined regions are drawn in grey.</p>"""


class MainWindow(QtWidgets.QMainWindow):
    def __init__(self, preferences: Preferences | None = None):
        super().__init__()
        self.preferences = preferences or Preferences()
        self.document = Document()
        self.landscape = None
        self.shown_scene: Scene | None = None   # what the view and the run belong to
        self.drawn_index = -1                # the row the view shows
        self.frames = 0

        self.controller = RunController(self)
        self.controller.stateChanged.connect(lambda _state: self._update_controls())
        self.controller.frameReady.connect(self._draw)
        self.controller.event.connect(self._run_event)
        self.controller.finished.connect(self._finished)
        self.controller.failed.connect(lambda message: self._warn("The computation failed", message))
        self.panel = ScenePanel()
        self.panel.sceneChanged.connect(self._scene_edited)
        self.view = SceneView()
        self.plots = LivePlots()
        self.readouts = Readouts()
        self._build_layout()
        self._build_actions()
        self._build_menus()
        self._build_toolbar()
        self._build_status()
        self.preferences.restore(self)
        self._update_controls()

    # -- layout ----------------------------------------------------------------------

    def _build_layout(self) -> None:
        self.setWindowIcon(QtGui.QIcon(str(resources.files("app") / "icons" / "rollball.svg")))
        scroll = QtWidgets.QScrollArea(widgetResizable=True)
        scroll.setWidget(self.panel)
        scroll.setMinimumWidth(340)
        scroll.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        dock = QtWidgets.QDockWidget("Scene", self, objectName="sceneDock")
        dock.setWidget(scroll)
        dock.setFeatures(QtWidgets.QDockWidget.DockWidgetFeature.DockWidgetMovable
                         | QtWidgets.QDockWidget.DockWidgetFeature.DockWidgetFloatable)
        self.addDockWidget(QtCore.Qt.DockWidgetArea.LeftDockWidgetArea, dock)

        splitter = QtWidgets.QSplitter(QtCore.Qt.Orientation.Vertical)
        top = QtWidgets.QWidget()
        v = QtWidgets.QVBoxLayout(top)
        v.setContentsMargins(0, 0, 0, 0)
        v.addWidget(self.view, 1)
        v.addWidget(self.readouts)
        splitter.addWidget(top)
        splitter.addWidget(self.plots)
        splitter.setStretchFactor(0, 4)
        splitter.setStretchFactor(1, 1)
        self.setCentralWidget(splitter)
        self.resize(1280, 860)

    def _action(self, text, slot, shortcut=None, tip=None, checkable=False, name=None) -> QtGui.QAction:
        action = QtGui.QAction(text, self, checkable=checkable)
        if shortcut:
            action.setShortcut(QtGui.QKeySequence(shortcut))
        if tip:
            action.setStatusTip(tip)
            action.setToolTip(f"{tip} ({action.shortcut().toString()})" if shortcut else tip)
        action.setObjectName(name or text.replace("&", "").replace("…", "").strip().lower().replace(" ", "_"))
        (action.toggled if checkable else action.triggered).connect(slot)
        return action

    def _build_actions(self) -> None:
        keys = QtGui.QKeySequence.StandardKey
        self.open_action = self._action("&Open Scene…", self.open_dialog, keys.Open, "Open a scene file")
        self.save_action = self._action("&Save Scene", self.save, keys.Save, "Save the scene")
        self.save_as_action = self._action("Save Scene &As…", self.save_as, keys.SaveAs,
                                           "Save the scene under a new name")
        self.export_action = self._action("&Export Trajectory CSV…", self.export_dialog, "Ctrl+E",
                                          "Write the computed trajectory as CSV")
        self.image_action = self._action("Save &Image…", self.save_image_dialog, "Ctrl+Shift+I",
                                         "Save the 3-D view as a PNG image")
        self.quit_action = self._action("&Quit", self.close, keys.Quit, "Quit RollBall")
        self.start_action = self._action("Start", self.start, "F5", "Start the run from t = 0")
        self.pause_action = self._action("Pause", self.toggle_pause, "Space", "Pause or resume playback",
                                         name="pause")
        self.step_action = self._action("Step", self.step_frame, "F6", "Advance one frame")
        self.stop_action = self._action("Stop", self.stop, "Shift+F5", "Stop the computation here")
        self.reset_action = self._action("Reset", self.reset, "Ctrl+R", "Back to t = 0")
        self.follow_action = self._action("&Follow Ball", self._follow, "F", "Camera follows the ball",
                                          checkable=True)
        self.camera_action = self._action("Reset &Camera", self.view.reset_camera, "Home", "Default camera")
        self.trail_action = self._action("Show &Trail", lambda on: self.view.trail.setVisible(on), "T",
                                         "Show the contact path", checkable=True)
        self.trail_action.setChecked(True)
        self.limits_action = self._action("Limits of the &Model", self.show_limits, None,
                                          "When the model stops being valid")
        self.about_action = self._action("&About RollBall", self.show_about, None, "Version and licence")
        for action in (self.start_action, self.pause_action, self.step_action, self.stop_action,
                       self.reset_action):
            action.setShortcutContext(QtCore.Qt.ShortcutContext.WindowShortcut)
        self.addActions([self.start_action, self.pause_action, self.step_action, self.stop_action,
                         self.reset_action])

    def _build_menus(self) -> None:
        bar = self.menuBar()
        files = bar.addMenu("&File")
        files.addAction(self.open_action)
        self.recent_menu = files.addMenu("Open &Recent")
        self.recent_menu.aboutToShow.connect(self._fill_recent)
        self.examples_menu = files.addMenu("E&xamples")
        self.examples_menu.setToolTipsVisible(True)
        for path, scene in example_scenes():
            summary = scene.description if len(scene.description) <= 70 else scene.description[:67] + "…"
            action = self.examples_menu.addAction(f"{path.stem} — {summary}")
            action.setToolTip(scene.description)
            action.setStatusTip(scene.description)
            action.setData(str(path))
            action.triggered.connect(lambda _=False, p=path: self.open_scene(p, remember=False))
        files.addSeparator()
        files.addActions([self.save_action, self.save_as_action])
        files.addSeparator()
        files.addActions([self.export_action, self.image_action])
        files.addSeparator()
        files.addAction(self.quit_action)
        run = bar.addMenu("&Run")
        run.addActions([self.start_action, self.pause_action, self.step_action, self.stop_action,
                        self.reset_action])
        view = bar.addMenu("&View")
        view.addActions([self.follow_action, self.trail_action, self.camera_action])
        helps = bar.addMenu("&Help")
        helps.addActions([self.limits_action, self.about_action])

    def _build_toolbar(self) -> None:
        bar = self.addToolBar("Run")
        bar.setObjectName("runToolbar")
        bar.setMovable(False)
        bar.setToolButtonStyle(QtCore.Qt.ToolButtonStyle.ToolButtonTextBesideIcon)
        style = self.style()
        icons = QtWidgets.QStyle.StandardPixmap
        for action, icon in ((self.start_action, icons.SP_MediaPlay), (self.pause_action, icons.SP_MediaPause),
                             (self.step_action, icons.SP_MediaSeekForward), (self.stop_action, icons.SP_MediaStop),
                             (self.reset_action, icons.SP_MediaSkipBackward)):
            action.setIcon(style.standardIcon(icon))
            bar.addAction(action)
        bar.addSeparator()
        bar.addWidget(QtWidgets.QLabel(" Playback "))
        self.speed = QtWidgets.QComboBox(objectName="speed")
        for label, value in SPEEDS:
            self.speed.addItem(label, value)
        self.speed.currentIndexChanged.connect(lambda: setattr(self.controller, "speed", self.speed.currentData()))
        self.speed.setCurrentIndex(3)
        self.speed.setToolTip("Simulated seconds per wall-clock second")
        bar.addWidget(self.speed)
        bar.addSeparator()
        self.follow_box = QtWidgets.QCheckBox("Follow ball", objectName="follow")
        self.follow_box.toggled.connect(self.follow_action.setChecked)
        self.follow_action.toggled.connect(self.follow_box.setChecked)
        bar.addWidget(self.follow_box)
        spacer = QtWidgets.QWidget()
        spacer.setSizePolicy(QtWidgets.QSizePolicy.Policy.Expanding, QtWidgets.QSizePolicy.Policy.Preferred)
        bar.addWidget(spacer)
        self.progress = QtWidgets.QProgressBar(objectName="progress", minimum=0, maximum=1000)
        self.progress.setFixedWidth(220)
        self.progress.setFormat("%p %")
        bar.addWidget(self.progress)

    def _build_status(self) -> None:
        self.state_label = QtWidgets.QLabel(objectName="state")
        self.state_label.setFixedWidth(150)  # text changes must not re-lay out the window
        self.message = QtWidgets.QLabel(objectName="message")
        self.message.setTextFormat(QtCore.Qt.TextFormat.PlainText)
        self.statusBar().addWidget(self.message, 1)
        self.statusBar().addPermanentWidget(self.state_label)

    # -- scene -----------------------------------------------------------------------

    @property
    def scene(self) -> Scene | None:
        return self.panel.scene()

    def open_scene(self, path, remember: bool = True) -> bool:
        """Load a scene file; on failure say why and keep the current scene."""
        path = Path(path)
        try:
            scene = Scene.load(path)
        except (SceneError, OSError) as error:
            self._warn("Cannot open scene", f"{path.name}: {error}")
            if remember:
                self.preferences.remove_recent(str(path.resolve()))
            return False
        if not self._may_discard():
            return False
        self.reset()
        self.document.opened(path, scene, example=not remember)
        if remember:
            self.preferences.add_recent(path)
            self.preferences.set_last_folder(path)
        self.panel.set_scene(scene)
        notes = self._use_scene(scene, redraw_camera=True)
        self.show_message(f"Opened {path.name}" + (f": {scene.description}" if scene.description else "")
                          + "".join(f" ({note})" for note in notes))
        return True

    def _scene_edited(self, scene: Scene) -> None:
        self._use_scene(scene)

    def _use_scene(self, scene: Scene, redraw_camera: bool = False) -> list[str]:
        """Show a valid scene; a change to what a run depends on resets the run. Returns notes
        on what the drawn landscape shows (no-fit and undefined regions)."""
        old = self.shown_scene
        landscape = landscape_for(scene.landscape)
        try:
            landscape.compiled  # noqa: B018 - compile now, so a run starts at once
        except Exception as error:  # numba refused generated code: keep what is shown
            self._warn("Cannot use this landscape", str(error))
            return []
        notes = []
        surface_changed = (old is None or old.landscape != scene.landscape or old.view != scene.view
                           or old.ball.radius != scene.ball.radius)
        if surface_changed:
            self.landscape = landscape
            facts = self.view.set_landscape(landscape, scene.view, scene.ball.radius)
            if facts["no_fit"]:
                notes.append("red: the ball does not fit there")
            if facts["undefined"]:
                notes.append("grey: the landscape is undefined there")
            self.show_message("; ".join(notes).capitalize())
        if redraw_camera:
            self.view.reset_camera()
        self.plots.set_duration(scene.duration)
        run_changed = old is None or _physics(old) != _physics(scene)
        if run_changed:
            if self.controller.state in (RUNNING, PAUSED):
                self.show_message("Scene changed: the run was reset")
            self.reset()
        self.shown_scene = scene
        self._update_title()
        return notes

    def _update_title(self) -> None:
        self.setWindowModified(self.dirty)
        self.setWindowTitle(self.document.title())

    @property
    def dirty(self) -> bool:
        return self.document.dirty(self.scene)

    def _may_discard(self) -> bool:
        """Ask before unsaved scene changes are lost; True to go on."""
        if not self.dirty:
            return True
        answer = self.ask_unsaved()
        if answer == QtWidgets.QMessageBox.StandardButton.Save:
            return self.save()
        return answer == QtWidgets.QMessageBox.StandardButton.Discard

    def ask_unsaved(self) -> QtWidgets.QMessageBox.StandardButton:
        buttons = QtWidgets.QMessageBox.StandardButton
        return QtWidgets.QMessageBox.question(self, "Unsaved changes", "The scene has unsaved changes. Save them?",
                                              buttons.Save | buttons.Discard | buttons.Cancel, buttons.Save)

    # -- files -----------------------------------------------------------------------

    def open_dialog(self) -> None:
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self, "Open scene", self.preferences.last_folder(),
                                                        SCENE_FILTER)
        if path:
            self.open_scene(path)

    def _fill_recent(self) -> None:
        self.recent_menu.clear()
        files = self.preferences.recent_files()
        for path in files:
            action = self.recent_menu.addAction(Path(path).name)
            action.setToolTip(path)
            action.setStatusTip(path)
            action.triggered.connect(lambda _=False, p=path: self.open_scene(p))
        if not files:
            self.recent_menu.addAction("(none)").setEnabled(False)
        self.recent_menu.addSeparator()
        self.recent_menu.addAction("Clear Recent", self.preferences.clear_recent).setEnabled(bool(files))

    def save(self) -> bool:
        if self.document.path is None:
            return self.save_as()
        return self.save_to(self.document.path)

    def save_as(self) -> bool:
        suggestion = str(Path(self.preferences.last_folder()) / f"{self.document.stem or 'scene'}.json")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Save scene", suggestion, SCENE_FILTER)
        return bool(path) and self.save_to(Path(path))

    def save_to(self, path: Path) -> bool:
        scene = self.panel.apply() or self.scene
        if self.panel.error_text:
            self.show_message(f"Saving the last valid scene ({self.panel.error_text})")
        if not self._write("save scene", path, scene.save):
            return False
        self.document.saved(path, scene)
        self.preferences.add_recent(path)
        self._update_title()
        self.show_message(f"Saved {Path(path).name}")
        return True

    def _write(self, what: str, path: Path, write) -> bool:
        """``write(path)`` (atomic); a failure is reported and leaves any old file as it was."""
        try:
            write(path)
        except OSError as error:
            self._warn(f"Cannot {what}", f"{path}: {error.strerror or error}. Nothing was changed.")
            return False
        self.preferences.set_last_folder(path)
        return True

    def export_dialog(self) -> None:
        suggestion = str(Path(self.preferences.last_folder()) / f"{self.document.stem or 'trajectory'}.csv")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Export trajectory", suggestion, CSV_FILTER)
        if path:
            self.export_csv(Path(path))

    def export_csv(self, path: Path) -> bool:
        simulation = self.controller.simulation
        if simulation is None or not self.controller.computed:
            return False
        trajectory = simulation.trajectory()
        if not self._write("export trajectory", path, trajectory.to_csv):
            return False
        self.show_message(f"Exported {len(trajectory):,} rows to {Path(path).name}")
        return True

    def save_image_dialog(self) -> None:
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Save image", str(Path(self.preferences.last_folder())
                                                        / "rollball.png"), "PNG images (*.png)")
        if path:
            self.save_image(Path(path))

    def save_image(self, path: Path) -> bool:
        """The 3-D view as a PNG, written atomically."""
        data = QtCore.QByteArray()
        buffer = QtCore.QBuffer(data)
        buffer.open(QtCore.QIODevice.OpenModeFlag.WriteOnly)
        self.view.grabFramebuffer().save(buffer, "PNG")
        if not self._write("save image", path, lambda target: atomic_write_bytes(target, bytes(data))):
            return False
        self.show_message(f"Saved {path.name}")
        return True

    # -- running ---------------------------------------------------------------------

    @property
    def state(self) -> str:
        return self.controller.state

    def start(self) -> None:
        """Start from t = 0 (or resume when paused)."""
        if self.state == PAUSED:
            self.toggle_pause()
            return
        self.panel.apply()
        scene = self.scene
        if scene is None:
            return
        self.reset()
        try:
            simulation = Simulation(scene, **recording(scene, record_every=self.panel.record_every.value()))
        except ValueError as error:
            self._warn("Cannot start", str(error))
            return
        if simulation.adaptive:
            note = f"Running adaptive steps to t = {scene.duration:g} s"
        else:
            every = simulation.record_every
            note = (f"Running {simulation.n_steps:,} steps"
                    + (f" (recording every {every}th step)" if every > 1 else ""))
        self.plots.set_duration(scene.duration)
        self.controller.start([Run(simulation, self.landscape)])
        self.show_message(note)

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
        self.show_message(f"Stopped at t = {self.controller.play_time:.4g} s")

    def reset(self) -> None:
        """Back to the start of the current scene; the computed run is dropped."""
        self.controller.reset()
        self.drawn_index = -1
        scene = self.scene
        if scene is not None and self.landscape is not None:
            self._draw_start(scene)
        self.plots.show_run(None, 0)
        self.view.set_liftoff(None)
        self.view.set_trail(np.zeros((0, 3)))
        self.progress.setValue(0)

    def _finished(self) -> None:
        simulation = self.controller.simulation
        status, text = simulation.status, simulation.message()
        if status is Status.OK:
            warnings = "".join(f"; {note}" for note in self._trajectory().warnings())
            self.show_message(f"Finished: {text}" + self._liftoff_note() + warnings, warning=bool(warnings))
        else:
            self.show_message(f"Stopped early ({status.value.replace('_', ' ')}): {text}", warning=True)

    def _trajectory(self) -> Trajectory:
        """The received rows as a trajectory (no copy)."""
        ball = self.controller.simulation.scene.ball
        return Trajectory(self.controller.buffer.rows, mass=ball.mass, radius=ball.radius,
                          gravity=self.controller.simulation.scene.gravity)

    def _liftoff_note(self) -> str:
        t = self.controller.simulation.liftoff_time
        return "" if t is None else f"; lift-off at t = {t:.4g} s (not physical from there on)"

    def _run_event(self, index: int, kind: str, t: float) -> None:
        if kind == "liftoff":
            self.view.set_liftoff(self.controller.runs[index].buffer.point_at(t))
            self.show_message(f"Lift-off at t = {t:.4g} s: the real ball would leave the surface "
                              f"here; the model keeps it on, so what follows is not physical", warning=True)

    # -- drawing ---------------------------------------------------------------------

    def _draw_start(self, scene: Scene) -> None:
        """The ball at its start position, before any run."""
        s, r = scene.start, scene.ball.radius
        d = self.landscape.evaluate(s.x, s.y)
        if not np.all(np.isfinite(d)):
            self.show_message(f"The landscape cannot be evaluated at the start point ({s.x:g}, {s.y:g})",
                              warning=True)
            return
        center = np.array([s.x, s.y, d[0]]) + r * unit_normal(d)
        self.view.set_ball(center, np.eye(3), r)
        self.readouts.clear()

    def _draw(self, force: bool = False) -> None:
        buffer = self.controller.buffer
        if buffer is None or len(buffer) == 0:
            return
        i = buffer.index_at(self.controller.play_time)
        if i == self.drawn_index and not force:
            return  # the same row as the last frame
        self.drawn_index = i
        row = buffer.rows[i]
        simulation = self.controller.simulation
        self.view.set_ball(row[CENTER], row[R].reshape(3, 3), simulation.scene.ball.radius)
        self.view.set_trail(buffer.trail(i, lift=0.004 * self.view.extent))
        self.readouts.show_row(0, buffer, i)
        self.frames += 1
        if force or self.frames % PLOT_EVERY == 0:
            self.plots.show_run(buffer, i)
        self.progress.setValue(int(round(1000 * min(1.0, row[T] / simulation.t_end))))

    def _update_controls(self) -> None:
        state, computed = self.state, self.controller.computed
        self.start_action.setEnabled(state != RUNNING)
        self.start_action.setText("Resume" if state == PAUSED else ("Restart" if state in (FINISHED, STOPPED)
                                                                   else "Start"))
        self.pause_action.setEnabled(state in (RUNNING, PAUSED))
        self.pause_action.setText("Resume" if state == PAUSED else "Pause")
        self.step_action.setEnabled(state in (READY, PAUSED, RUNNING))
        self.stop_action.setEnabled(state in (RUNNING, PAUSED))
        self.reset_action.setEnabled(state != READY)
        self.export_action.setEnabled(computed and self.controller.simulation is not None)
        words = {READY: "Ready", RUNNING: "Running", PAUSED: "Paused", FINISHED: "Finished", STOPPED: "Stopped"}
        self.state_label.setText(words[state] if computed or state in (READY, STOPPED, FINISHED)
                                 else f"{words[state]} (computing…)")

    def _follow(self, on: bool) -> None:
        self.view.set_follow(on, self.scene.ball.radius if on and self.scene else None)

    def show_message(self, text: str, warning: bool = False) -> None:
        self.message.setText(text)
        self.message.setToolTip(text)  # long messages are cut at the window's edge
        self.message.setStyleSheet("color: #b03a00; font-weight: bold;" if warning else "")

    def _warn(self, title: str, text: str) -> None:
        self.show_message(text, warning=True)
        QtWidgets.QMessageBox.warning(self, title, text)

    def show_limits(self) -> None:
        QtWidgets.QMessageBox.information(self, "Limits of the model", LIMITS_TEXT)

    def show_about(self) -> None:
        QtWidgets.QMessageBox.about(self, "About RollBall",
                                    f"<b>RollBall {__version__}</b><p>A solid ball rolling without slipping on "
                                    f"z = f(x, y). Euler, RK4 and Lawson5, classic or Munthe-Kaas.</p>")

    # -- closing ---------------------------------------------------------------------

    def closeEvent(self, event: QtGui.QCloseEvent) -> None:
        if not self._may_discard():
            event.ignore()
            return
        self.preferences.save(self)
        self.reset()  # stops the worker and lets go of the run's arrays
        event.accept()


def _physics(scene: Scene) -> tuple:
    """What a run depends on (not the drawn grid or the description)."""
    return (scene.landscape, scene.gravity, scene.ball, scene.start, scene.integrator, scene.duration)


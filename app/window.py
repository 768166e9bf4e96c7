"""The main window: inputs around the 3-D view, run controls, readouts, plots, files."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from rollball import Scene, SceneError, Simulation, Status, __version__, resources
from rollball.examples import example_scenes
from rollball.geometry import reachable_height, unit_normal
from rollball.simulation import recording
from rollball.text import shown
from rollball.trajectory import CENTER, CONTACT, R

from . import help as helps
from .closeup import CloseUp
from .compare_mode import CompareMode
from .controller import FINISHED, PAUSED, READY, RUNNING, STOPPED, Run, RunController
from .exports import Exports
from .inputs import ScenePanel, compile_reason
from .modes import DEFAULT_SIZE, Modes, fitted, place_over
from .parameters import valued
from .plots import LivePlots
from .preferences import Preferences
from .presentation import TEXT_SIZES, Presentation
from .session import SceneSession, changes, run_spec
from .readouts import Readouts
from .speed_window import SpeedWindow
from .sweep_dialog import SweepDialog
from .timeline import Marker, TimeSlider
from .view3d import SceneView
from .warmup import WarmUp

PLOT_INTERVAL = 0.1   # s between plot updates while playing (at most 10/s; at every frame where frames are slower)
SPEEDS = (("0.1×", 0.1), ("0.25×", 0.25), ("0.5×", 0.5), ("Real time", 1.0), ("2×", 2.0),
          ("5×", 5.0), ("10×", 10.0), ("As fast as computed", math.inf))
SCENE_FILTER = "RollBall scenes (*.json);;All files (*)"
LIFTOFF_COLOR, STOP_COLOR = "#ff8c00", "#c0392b"   # markers on the time slider
START_WORDS = {READY: ("Start", "Start the run from t = 0"),                # what Start does, by state
               PAUSED: ("Resume", "Resume playback from where it was paused"),
               FINISHED: ("Restart", "Run again from t = 0"),
               STOPPED: ("Restart", "Run again from t = 0")}


class MainWindow(QtWidgets.QMainWindow):
    def __init__(self, preferences: Preferences | None = None):
        super().__init__()
        self.preferences = preferences or Preferences()
        self.session = SceneSession(self.show_scene, self)
        self.document = self.session.document
        self.landscape = None
        self.drawn_index = -1                # the row the view shows
        self.plotted_at = -math.inf          # when the plots were last brought up to the shown time
        self.warmup = WarmUp(self)          # compiling the integrator in the background
        self.warmup.readied.connect(self._warmed)
        self.warmup.ended.connect(self._warmed)
        self.start_waiting = False          # Start was pressed meanwhile

        self.controller = RunController(self)
        self.controller.stateChanged.connect(self._state_changed)
        self.controller.frameReady.connect(self._draw)
        self.controller.event.connect(self._run_event)
        self.controller.finished.connect(self._finished)
        self.controller.failed.connect(lambda message: self._warn("The computation failed", message))
        self.panel = ScenePanel()
        self.panel.sceneChanged.connect(self._scene_edited)
        self.view = SceneView()
        self.closeup_frame = QtWidgets.QFrame(self.view, objectName="closeupFrame")
        self.closeup_frame.setStyleSheet("#closeupFrame { border: 2px solid #333; background: #333; }")
        self.closeup = CloseUp()
        frame_layout = QtWidgets.QVBoxLayout(self.closeup_frame)
        frame_layout.setContentsMargins(2, 2, 2, 2)
        frame_layout.addWidget(self.closeup)
        self.closeup_frame.hide()
        self.timeline = TimeSlider()
        self.timeline.seeked.connect(self.seek)
        self.plots = LivePlots()
        self.speed_window: SpeedWindow | None = None   # made when first asked for
        self.readouts = Readouts()
        self.undo_stack = self.session.undo
        self.undo_stack.cleanChanged.connect(lambda _clean: self._update_controls())
        self.help_window: helps.HelpWindow | None = None
        self.exports = Exports(self)   # CSV, PNG, MP4 and GIF
        self.view.installEventFilter(self)   # keeps the close-up in the view's corner
        self._build_layout()
        self._build_actions()
        self._build_menus()
        self._build_toolbar()
        self._build_status()
        self.compare = CompareMode(self)
        self.compare.panel.followChanged.connect(lambda _i: self._follow(self.follow_action.isChecked()))
        self.presentation = Presentation(self)
        self.presentation.add_actions([self.scene_panel_action, self.presentation_action])
        self.modes = Modes(self)
        self.preferences.restore(self)
        self.modes.restored()   # the editing layout, whatever the last session showed
        self._set_text_size(self.preferences.font_scale())
        self._set_help_topics()
        self._update_controls()

    # -- layout ----------------------------------------------------------------------

    def _build_layout(self) -> None:
        self.setWindowIcon(QtGui.QIcon(str(resources.path("icons", "rollball.svg"))))
        scroll = QtWidgets.QScrollArea(widgetResizable=True)
        scroll.setWidget(self.panel)
        scroll.setMinimumWidth(340)
        scroll.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.scene_dock = dock = QtWidgets.QDockWidget("Scene", self, objectName="sceneDock")
        dock.setWidget(scroll)
        dock.setFeatures(QtWidgets.QDockWidget.DockWidgetFeature.DockWidgetMovable
                         | QtWidgets.QDockWidget.DockWidgetFeature.DockWidgetFloatable)
        self.addDockWidget(QtCore.Qt.DockWidgetArea.LeftDockWidgetArea, dock)

        self.splitter = splitter = QtWidgets.QSplitter(QtCore.Qt.Orientation.Vertical)
        top = QtWidgets.QWidget()
        v = QtWidgets.QVBoxLayout(top)
        v.setContentsMargins(0, 0, 0, 0)
        v.addWidget(self.view, 1)
        v.addWidget(self.timeline)
        v.addWidget(self.readouts)
        splitter.addWidget(top)
        self.bottom = QtWidgets.QStackedWidget()   # the live plots, or compare mode's error plots
        self.bottom.addWidget(self.plots)
        splitter.addWidget(self.bottom)
        splitter.setStretchFactor(0, 4)
        splitter.setStretchFactor(1, 1)
        self.setCentralWidget(splitter)
        screen = self.screen() or QtWidgets.QApplication.primaryScreen()
        self.resize(fitted(DEFAULT_SIZE, screen.availableGeometry()))

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
        self.export_action = self._action("&Export Trajectory CSV…", self.exports.export_dialog, "Ctrl+E",
                                          "Write the computed trajectory as CSV")
        self.image_action = self._action("Save &Image…", self.exports.save_image_dialog, "Ctrl+Shift+I",
                                         "Save the 3-D view as a PNG image (1×, 2×, 4×; caption; plots)")
        self.animation_action = self._action("Export &Animation…", self.exports.export_animation_dialog, "Ctrl+Shift+E",
                                             "Write the run's playback as an MP4 video or a GIF")
        self.revert_action = self._action("Re&vert Scene", self.revert, None,
                                          "Back to the scene as it was opened or last saved")
        self.undo_action = self.undo_stack.createUndoAction(self, "&Undo")
        self.undo_action.setShortcuts([QtGui.QKeySequence("Ctrl+Z")])
        self.redo_action = self.undo_stack.createRedoAction(self, "&Redo")
        self.redo_action.setShortcuts([QtGui.QKeySequence("Ctrl+Shift+Z"), QtGui.QKeySequence("Ctrl+Y")])
        self.undo_action.setStatusTip("Undo the last change of the scene's fields")
        self.redo_action.setStatusTip("Redo the change undone last")
        self.quit_action = self._action("&Quit", self.close, keys.Quit, "Quit RollBall")
        self.start_action = self._action("Start", self.start, "F5", "Start the run from t = 0")
        self.pause_action = self._action("Pause", self.toggle_pause, "Space", "Pause playback (again: resume)",
                                         name="pause")
        self.pause_action.setCheckable(True)   # held down while paused; Start says Resume meanwhile
        self.step_action = self._action("Step", self.step_frame, "F6", "Advance one frame")
        self.stop_action = self._action("Stop", self.stop, "Shift+F5", "Stop the computation here")
        self.reset_action = self._action("Reset", self.reset, "Ctrl+R", "Back to t = 0")
        self.follow_action = self._action("&Follow Ball", self._follow, "F", "Camera follows the ball",
                                          checkable=True)
        self.camera_action = self._action("Reset &Camera", self.view.reset_camera, "C", "Default camera")
        self.back_action = self._action("Frame Back", lambda: self.controller.step(-1), "Left",
                                        "Show the moment one frame earlier")
        self.forward_action = self._action("Frame Forward", lambda: self.controller.step(1), "Right",
                                           "Show the moment one frame later")
        self.first_action = self._action("Go to Start", lambda: self.seek(0.0), "Home", "Show t = 0")
        self.last_action = self._action("Go to End", lambda: self.seek(math.inf), "End",
                                        "Show the last computed moment")
        self.liftoff_action = self._action("Go to &Lift-off", self.go_to_liftoff, "L",
                                           "Show the moment the real ball would leave the surface")
        self.presentation_action = self._action("&Presentation", lambda on: self.modes.set_presentation(on), "F11",
                                                "Full screen, large text, close-up of the ball (Esc leaves)",
                                                checkable=True)
        self.leave_action = self._action("Leave Presentation", lambda: self.presentation_action.setChecked(False),
                                         "Esc", "Back from presentation mode")
        self.scene_panel_action = self._action("Scene", lambda on: self.modes.choose_scene_panel(on), None,
                                               "Show or hide the scene panel", checkable=True,
                                               name="scene_panel")
        self.reset_layout_action = self._action("Reset &Layout", lambda: self.modes.reset_layout(), None,
                                                "The panels where they were at first, the window at its "
                                                "default size", name="reset_layout")
        self.leave_action.setEnabled(False)
        self.closeup_action = self._action("&Close-up", lambda on: self.modes.choose_closeup(on), "Z",
                                           "A close-up following the ball in the corner of the view",
                                           checkable=True)
        self.compare_action = self._action("&Compare Methods", self._compare_toggled, "Ctrl+K",
                                           "Several methods side by side on this scene, with their true errors",
                                           checkable=True)
        self.speed_error_action = self._action("&Speed against Error…", self.show_speed_against_error, None,
                                               "Every method on this scene: error against compute time "
                                               "and against step size")
        self.trail_action = self._action("Show &Trail", self.view.set_trails_visible, "T",
                                         "Show the contact path", checkable=True)
        self.trail_action.setChecked(True)
        self.mark_action = self._action("Ball &Marker", self.view.set_marks_visible, "M",
                                        "A ring around the ball where it is drawn smaller than 30 pixels (a mark "
                                        "to see it from afar; the ball inside is to scale)", checkable=True,
                                        name="ball_marker")
        self.mark_action.setChecked(True)
        self.model_help_action = self._action("The &Model", lambda: self.show_help("model.html"), None,
                                              "The equations of motion, lift-off, no-fit, Munthe-Kaas")
        self.plots_help_action = self._action("Reading the &Plots", lambda: self.show_help("plots.html"), None,
                                              "What the plots, readouts and colours say")
        self.compare_help_action = self._action("&Comparing Methods", lambda: self.show_help("compare.html"), None,
                                                "Compare mode, speed against error, sweeps; which method when")
        self.keys_help_action = self._action("&Keyboard Shortcuts", lambda: self.show_help("keys"), None,
                                             "Every shortcut of the menus")
        self.context_help_action = self._action("Help on This", self.context_help, "F1",
                                                "Help on what the mouse points at")
        self.limits_action = self._action("Limits of the Model", lambda: self.show_help("model.html#liftoff"),
                                          None, "When the model stops being valid")
        self.sweep_action = self._action("&Sweep…", self.open_sweep, None,
                                         "Run the scene over a grid of start values or parameters")
        self.about_action = self._action("&About RollBall", self.show_about, None, "Version and licence")
        keyed = [self.start_action, self.pause_action, self.step_action, self.stop_action, self.reset_action,
                 self.back_action, self.forward_action, self.first_action, self.last_action, self.leave_action,
                 self.context_help_action]
        for action in keyed:
            action.setShortcutContext(QtCore.Qt.ShortcutContext.WindowShortcut)
        self.addActions(keyed)

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
        files.addAction(self.revert_action)
        files.addSeparator()
        files.addActions([self.export_action, self.image_action, self.animation_action])
        files.addSeparator()
        files.addAction(self.quit_action)
        edit = bar.addMenu("&Edit")
        edit.addActions([self.undo_action, self.redo_action])
        run = bar.addMenu("&Run")
        run.addActions([self.start_action, self.pause_action, self.step_action, self.stop_action,
                        self.reset_action])
        run.addSeparator()
        run.addActions([self.back_action, self.forward_action, self.first_action, self.last_action,
                        self.liftoff_action])
        run.addSeparator()
        run.addAction(self.compare_action)
        view = bar.addMenu("&View")
        view.addActions([self.presentation_action, self.closeup_action])
        sizes = view.addMenu("Text &Size")
        self.text_size_group = QtGui.QActionGroup(self)
        for label, scale in TEXT_SIZES:
            action = sizes.addAction(label)
            action.setCheckable(True)
            action.setData(scale)
            action.triggered.connect(lambda _=False, k=scale: self._set_text_size(k, remember=True))
            self.text_size_group.addAction(action)
        view.addSeparator()
        view.addActions([self.follow_action, self.trail_action, self.mark_action, self.camera_action])
        view.addSeparator()
        view.addActions([self.scene_panel_action, self.reset_layout_action])
        analysis = bar.addMenu("&Analysis")
        analysis.addActions([self.speed_error_action, self.sweep_action])
        help_menu = bar.addMenu("&Help")
        help_menu.addActions([self.model_help_action, self.plots_help_action, self.compare_help_action,
                              self.keys_help_action,
                              self.context_help_action])
        help_menu.addSeparator()
        help_menu.addActions([self.limits_action, self.about_action])

    def _build_toolbar(self) -> None:
        self.run_toolbar = bar = self.addToolBar("Run")
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
        bar.addAction(self.compare_action)
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
        self.progress.setFixedWidth(150)   # the whole toolbar fits a 1024-pixel window
        self.progress.setFormat("%p %")
        bar.addWidget(self.progress)

    def _build_status(self) -> None:
        self.state_label = QtWidgets.QLabel(objectName="state")
        self.state_label.setFixedWidth(150)  # text changes must not re-lay out the window
        self.message = StatusMessage(objectName="message")
        self.message.setTextFormat(QtCore.Qt.TextFormat.PlainText)
        self.message.setWordWrap(True)   # a long message takes a second line rather than being cut
        self.statusBar().addWidget(self.message, 1)
        self.statusBar().addPermanentWidget(self.state_label)

    # -- scene -----------------------------------------------------------------------

    @property
    def scene(self) -> Scene | None:
        return self.panel.scene()

    def open_scene(self, path, remember: bool = True) -> bool:
        """Load a scene file; on failure say why and keep the current scene."""
        path = Path(path)
        try:  # a named pipe or a device is refused before it is opened (it would block)
            scene = Scene.load(path)
        except (SceneError, OSError) as error:
            reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
            self._warn("Cannot open scene", f"{shown(path.name)}: {reason}")
            if remember:
                self.preferences.remove_recent(str(path.resolve()))
            return False
        if not self._may_discard():
            return False
        self.reset()
        self.session.opened(path, scene, example=not remember)
        if remember:
            self.preferences.add_recent(path)
            self.preferences.set_last_folder(path)
        self.panel.set_scene(scene)
        notes = self._use_scene(scene, redraw_camera=True)
        self.show_message(f"Opened {path.name}" + (f": {scene.description}" if scene.description else "")
                          + "".join(f" ({note})" for note in notes))
        return True

    def _scene_edited(self, scene: Scene) -> None:
        old = self.session.shown
        self._use_scene(scene)
        self.session.edited(old, scene, self.panel.gesture)

    def show_scene(self, scene: Scene) -> None:
        """Put a scene into the fields and the view (undo, redo, revert)."""
        self.panel.set_scene(scene)
        self._use_scene(scene)

    def revert(self) -> None:
        """Back to the scene as opened or last saved (itself undoable)."""
        if not self.session.revert(self.scene):
            return
        self.show_message(f"Reverted to {self.document.name}")

    def _use_scene(self, scene: Scene, redraw_camera: bool = False) -> list[str]:
        """Show a valid scene; a change to what a run depends on resets the run. Returns notes
        on what the drawn landscape shows (no-fit and undefined regions)."""
        old = self.session.shown
        landscape = valued(scene)   # with the parameters' values: new values compile nothing
        try:
            landscape.compiled  # noqa: B018 - compile now, so a run starts at once
        except Exception as error:  # numba refused generated code: keep what is shown
            self._warn("Cannot use this landscape", compile_reason(error))
            return []
        notes = []
        changed = changes(old, scene)
        if changed.surface:
            self.landscape = landscape
            start = landscape.evaluate(scene.start.x, scene.start.y)
            reachable = reachable_height(start, scene) if np.all(np.isfinite(start)) else np.inf
            facts = self.view.set_landscape(landscape, scene.view, scene.ball.radius, reachable)
            self.closeup.set_landscape(landscape, scene.ball.radius, self.view.z_span)
            if facts["no_fit"]:
                notes.append("red: the ball does not fit there")
            if facts["undefined"]:
                notes.append("grey: the landscape is undefined there")
            if facts["cut"]:
                notes.append("cut level where the ball's energy cannot take it")
            if facts["coarse"]:
                notes.append("the grid spacing is too coarse for this landscape, the drawing is misleading: "
                             "choose a smaller area or spacing")
            self.show_message("; ".join(notes).capitalize())
        self.plots.set_duration(scene.duration)
        if changed.run:
            if self.controller.state in (RUNNING, PAUSED):
                self.show_message("Scene changed: the run was reset")
            self.reset()
        if redraw_camera or changed.grid:
            self.view.reset_camera()   # after reset(), so the ball stands at the start
        elif changed.surface:
            self.view.refresh_axes()   # new heights (a slider): the camera stays
        self.session.shown = scene
        self.compare.scene_changed(scene)
        self._update_title()
        return notes

    def _update_title(self) -> None:
        self.setWindowModified(self.dirty)
        self.revert_action.setEnabled(self.dirty)
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
            self._warn(f"Cannot {what}", f"{shown(path)}: {error.strerror or error}. Nothing was changed.")
            return False
        self.preferences.set_last_folder(path)
        return True

    # -- running ---------------------------------------------------------------------

    @property
    def state(self) -> str:
        return self.controller.state

    @property
    def preparing(self) -> QtCore.QProcess | None:
        """The integrator's warm-up process while it runs."""
        return self.warmup.process

    def prepare_integrator(self, command: list[str] | None = None) -> None:
        """Compile the integrator for every method in a process of its own, from launch, the
        current scene's method first (``WarmUp``). A Start meanwhile waits until its method is
        ready, saying so with a busy indicator, and the run starts by itself."""
        scene = self.scene
        self.warmup.start(command or WarmUp.command(None if scene is None else run_spec(scene)))

    def _must_wait(self) -> bool:
        """Whether a Start now would compile what the warm-up is compiling."""
        scene = self.scene
        return self.warmup.must_wait(None if self.compare.active or scene is None else run_spec(scene))

    def stop_preparing(self) -> None:
        self.warmup.stop()

    def _warmed(self) -> None:
        """A variant is ready (or the warm-up has ended): a start waiting for it goes."""
        if self.warmup.process is None:
            self.progress.setRange(0, 1000)
        if self.start_waiting and not self._must_wait():
            self.start_waiting = False
            self.start()

    def start(self) -> None:
        """Start from t = 0 (or resume when paused)."""
        if self.state == PAUSED:
            self.toggle_pause()
            return
        if self._must_wait():
            self.start_waiting = True
            self.progress.setRange(0, 0)   # busy
            self.show_message("Preparing the integrator (first run only)… the run starts by itself "
                              "when it is ready")
            self._update_controls()
            return
        self.panel.apply()
        scene = self.scene
        if scene is None:
            self._warn("Cannot start", f"There is no valid scene to run: {self.panel.error_text}")
            return
        stale = self.panel.error_text  # the fields as typed do not make a scene: say what runs
        self.reset()
        if self.compare.active:
            try:
                self.compare.start(scene)
            except ValueError as error:
                self._warn("Cannot compare", str(error))
            self._follow(self.follow_action.isChecked())
            return
        try:
            simulation = Simulation(scene, **recording(scene, record_every=self.panel.record_every.value()))
        except Exception as error:  # every refusal is said, whatever raised it
            self._warn("Cannot start", str(error) if isinstance(error, ValueError)
                       else f"{type(error).__name__}: {error}")
            return
        if simulation.adaptive:
            note = f"Running adaptive steps to t = {scene.duration:g} s"
        else:
            every = simulation.record_every
            note = (f"Running {simulation.n_steps:,} steps"
                    + (f" (recording every {every}th step)" if every > 1 else ""))
        self.plots.set_duration(scene.duration)
        self.timeline.set_span(simulation.t_end)
        self.controller.start([Run(simulation, self.landscape)])
        self.show_message(note + (f" of the last valid scene (not the fields: {stale})" if stale else ""),
                          warning=bool(stale))

    def show_speed_against_error(self) -> None:
        """Compare every method on the current scene, in a window of its own."""
        self.panel.apply()
        if self.scene is None:
            return
        if self.speed_window is None:
            self.speed_window = SpeedWindow(self)
            self.speed_window.runChosen.connect(self.load_run)
            place_over(self.speed_window, self)
        self.speed_window.compute(self.scene)

    def load_run(self, result) -> None:
        """Run the scene with a comparison run's method and step (or tolerance)."""
        data = self.scene.to_dict()
        integrator = data["integrator"]
        integrator.update(method=result.spec.method, munthe_kaas=result.spec.munthe_kaas)
        if result.dt is not None:
            integrator["dt"] = result.dt
        else:
            integrator.update(rtol=result.rtol, atol=result.atol)
        scene = Scene.from_dict(data)
        self.compare_action.setChecked(False)
        self.session.load(self.scene, scene, "Load Run from Speed against Error")
        self.start()
        self.activateWindow()

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
        self.show_message(f"Stopped at t = {t:.4g} s" + (self._liftoff_note() if liftoff is not None and liftoff <= t
                                                         else "") + " (what was computed can be exported)")

    def reset(self) -> None:
        """Back to the start of the current scene; the computed run is dropped."""
        self.start_waiting = False
        self.progress.setRange(0, 1000)
        self.controller.reset()
        self.drawn_index = -1
        self.view.set_runs(None)
        self.readouts.set_runs([None])
        self.compare.clear()   # no results of runs that are gone
        scene = self.scene
        if scene is not None and self.landscape is not None:
            self._draw_start(scene)
        self.plots.show_run(None, 0)
        self.plots.set_cursor(None)
        self.timeline.set_span(0.0)
        self.view.set_liftoff(None)
        self.view.set_trail(np.zeros((0, 3)))
        self.progress.setValue(0)

    def _finished(self) -> None:
        if self.compare.active:
            self.compare.finished()
            return
        simulation = self.controller.simulation
        status, text = simulation.status, simulation.message()
        liftoff = self._liftoff_note()   # every event of the run stays in its last word
        if status is Status.OK:
            warnings = "".join(f"; {note}" for note in self.controller.runs[0].trajectory().warnings())
            self.show_message(f"Finished: {text}" + liftoff + warnings, warning=bool(warnings or liftoff))
        else:
            self.show_message(f"Stopped early ({status.value.replace('_', ' ')}): {text}" + liftoff, warning=True)

    def _liftoff_note(self) -> str:
        t = self.controller.simulation.liftoff_time
        return "" if t is None else f"; lift-off at t = {t:.4g} s (not physical from there on)"

    def _run_event(self, index: int, kind: str, t: float) -> None:
        if kind == "liftoff":
            self.view.add_liftoff(self.controller.runs[index].buffer.point_at(t))
            who = f"{self.controller.runs[index].label}: " if self.compare.active else ""
            self.show_message(f"{who}Lift-off at t = {t:.4g} s: the real ball would leave the surface "
                              f"here; the model keeps it on, so what follows is not physical", warning=True)

    # -- drawing ---------------------------------------------------------------------

    def _draw_start(self, scene: Scene) -> None:
        """The ball at its start position, before any run."""
        s, r = scene.start, scene.ball.radius
        d = self.landscape.evaluate(s.x, s.y)
        valid = bool(np.all(np.isfinite(d)))
        self.view.ball.setVisible(valid)   # no ball left hanging where the start was
        if not valid:
            self.show_message(f"The landscape cannot be evaluated at the start point ({s.x:g}, {s.y:g})",
                              warning=True)
            return
        center = np.array([s.x, s.y, d[0]]) + r * unit_normal(d)
        self.view.set_ball(center, np.eye(3), r)
        self._show_closeup_at(center, np.eye(3), np.array([s.x, s.y]), np.zeros((0, 3)))
        self.readouts.clear()

    def _draw(self, force: bool = False) -> None:
        runs, t = self.controller.runs, self.controller.play_time
        if not runs or all(len(run.buffer) == 0 for run in runs):
            return
        indices = tuple(run.index_at(t) for run in runs)
        if indices == self.drawn_index and not force:
            return  # the same rows as the last frame
        self.drawn_index = indices
        radius = runs[0].simulation.scene.ball.radius
        followed = self.view.followed
        for k, (run, i) in enumerate(zip(runs, indices)):
            if len(run.buffer):
                row = run.buffer.rows[i]
                trail = run.buffer.trail(i, lift=0.3)   # 0.3 r above the contact point
                self.view.set_ball(row[CENTER], row[R].reshape(3, 3), radius, k)
                self.view.set_trail(trail, k)
                if k == followed:
                    self._show_closeup_at(row[CENTER], row[R].reshape(3, 3), row[CONTACT], trail, run.color)
                self.readouts.show_row(k, run.buffer, i)
        followed = self.compare.followed if self.compare.followed < len(runs) else 0
        if len(runs[followed].buffer):   # the time of the moment drawn, as its readout says it
            self.timeline.set_time(t, shown=float(runs[followed].buffer.t[indices[followed]]))
        if force or time.perf_counter() - self.plotted_at >= PLOT_INTERVAL:
            self._plot()   # in the same frame as the 3-D view: the window is composed once
        shown = min(float(run.buffer.t[i]) for run, i in zip(runs, indices) if len(run.buffer))
        self.progress.setValue(int(round(1000 * min(1.0, shown / self.controller.t_end))))

    def _plot(self) -> None:
        """Bring the plots, and the time line's computed span and events, up to the shown time."""
        self.plotted_at = time.perf_counter()
        runs, t = self.controller.runs, self.controller.play_time
        if self.compare.active:
            self.compare.error_plots.show_time(t)
        elif runs and len(runs[0].buffer):
            # while playing, the curves grow with the ball; otherwise they show all that is computed
            buffer = runs[0].buffer
            i = buffer.index_at(t)
            self.plots.show_run(buffer, i if self.state == RUNNING else len(buffer) - 1)
            self.plots.set_cursor(buffer.t[i])
        if runs:
            self.timeline.set_available(self.controller.end_time)
            self._show_events()

    def _state_changed(self, state: str) -> None:
        self._update_controls()
        if state == PAUSED:
            self._plot()   # the plots catch up with the ball where it stopped

    def _update_controls(self) -> None:
        state, computed = self.state, self.controller.computed
        text, tip = START_WORDS.get(state, START_WORDS[READY])
        self.start_action.setEnabled(state != RUNNING)
        self.start_action.setText(text)
        self.start_action.setStatusTip(tip)
        self.start_action.setToolTip(f"{tip} ({self.start_action.shortcut().toString()})")
        self.pause_action.setEnabled(state in (RUNNING, PAUSED))
        self.pause_action.setChecked(state == PAUSED)
        self.step_action.setEnabled(state in (READY, PAUSED, RUNNING))
        self.stop_action.setEnabled(state in (RUNNING, PAUSED))
        self.reset_action.setEnabled(state != READY)
        self.export_action.setEnabled((computed or state == STOPPED) and self.controller.simulation is not None)
        self.animation_action.setEnabled(bool(self.controller.runs))
        self.revert_action.setEnabled(self.dirty)
        for action in (self.back_action, self.forward_action, self.first_action, self.last_action):
            action.setEnabled(bool(self.controller.runs))
        self.liftoff_action.setEnabled(self._liftoff_time() is not None)
        if self.controller.runs:
            self.timeline.set_available(self.controller.end_time)
            self._show_events()
        words = {READY: "Ready", RUNNING: "Running", PAUSED: "Paused", FINISHED: "Finished", STOPPED: "Stopped"}
        doing = "compiling…" if self.controller.compiling else "computing…"
        self.state_label.setText("Preparing…" if self.start_waiting
                                 else words[state] if computed or state in (READY, STOPPED, FINISHED)
                                 else f"{words[state]} ({doing})")

    def _follow(self, on: bool) -> None:
        self.view.set_follow(on, self.scene.ball.radius if on and self.scene else None, index=self.compare.followed)

    def open_sweep(self) -> SweepDialog:
        """Analysis → Sweep…: a sweep of the current scene; a clicked run's scene is loaded here."""
        dialog = SweepDialog(self.scene, self)
        dialog.setAttribute(QtCore.Qt.WidgetAttribute.WA_DeleteOnClose)
        dialog.startChosen.connect(self.load_start)
        place_over(dialog, self)
        dialog.show()
        return dialog

    def load_start(self, scene: Scene) -> None:
        """Show a run of a sweep in the fields and the view, ready to run (undoable, not saved)."""
        self.session.load(self.scene, scene, "Load Run from Sweep")
        self.show_message("Start loaded from the sweep: press Start to run it")

    def show_message(self, text: str, warning: bool = False) -> None:
        self.message.setText(text)
        self.message.setToolTip(text)  # long messages are cut at the window's edge
        self.message.setStyleSheet("color: #b03a00; font-weight: bold;" if warning else "")

    def _warn(self, title: str, text: str) -> None:
        """Say it in the status bar and in a dialog, as plain text (a file's text is never markup)."""
        self.show_message(text, warning=True)
        QtWidgets.QMessageBox.warning(self, title, _plain(text))

    def show_about(self) -> None:
        QtWidgets.QMessageBox.about(self, "About RollBall",
                                    f"<b>RollBall {__version__}</b><p>A solid ball rolling without slipping on "
                                    f"z = f(x, y). Euler, RK4 and Lawson5, classic or Munthe-Kaas.</p>")

    # -- the time shown --------------------------------------------------------------

    def seek(self, t: float) -> None:
        """Show the moment t of the computed run (held within what is computed)."""
        self.controller.seek(t)

    def _liftoff_time(self) -> float | None:
        simulation = self.controller.simulation
        return simulation.liftoff_time if simulation is not None else None

    def go_to_liftoff(self) -> None:
        t = self._liftoff_time()
        if t is not None:
            self.seek(t)

    def _show_events(self) -> None:
        """Lift-off and an early stop as markers on the time slider and links beside it."""
        simulation = self.controller.simulation
        events = []
        if simulation.liftoff_time is not None:
            events.append(Marker(simulation.liftoff_time, LIFTOFF_COLOR, f"lift-off at t = {simulation.liftoff_time:.4g} s"))
        if simulation.status not in (None, Status.OK, Status.ABORTED) and len(self.controller.buffer):
            t = self.controller.buffer.end_time
            events.append(Marker(t, STOP_COLOR, f"{simulation.status.value.replace('_', ' ')} at t = {t:.4g} s"))
        if [m.text for m in events] != [m.text for _, m in self.timeline.slider.markers]:
            self.timeline.set_markers(events)
            self.liftoff_action.setEnabled(simulation.liftoff_time is not None)

    # -- presentation, close-up, text size ------------------------------------------

    def _compare_toggled(self, on: bool) -> None:
        if on != self.modes.compare:
            self.compare.set_active(on)
            self.modes.set_compare(on)

    def show_closeup(self, on: bool) -> None:
        self.closeup_frame.setVisible(on)
        self._place_closeup()
        if not on:
            return
        if self.controller.runs:
            self._draw(force=True)
        elif self.scene is not None and self.landscape is not None:
            self._draw_start(self.scene)

    def _place_closeup(self) -> None:
        w = max(160, round(0.3 * self.view.width()))
        h = round(0.75 * w)
        self.closeup_frame.setGeometry(self.view.width() - w - 8, 8, w, h)

    def _show_closeup_at(self, center, R, contact, trail, color: str | None = None) -> None:
        if self.closeup.isVisible():
            self.closeup.show_ball(center, R, contact, trail, self.view.opts["azimuth"], self.view.opts["elevation"],
                                   color)

    def changeEvent(self, event) -> None:
        super().changeEvent(event)
        if event.type() == QtCore.QEvent.Type.WindowStateChange and hasattr(self, "modes"):
            self.modes.window_changed()

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        if hasattr(self, "modes"):
            self.modes.window_changed()

    def moveEvent(self, event) -> None:
        super().moveEvent(event)
        if hasattr(self, "modes"):
            self.modes.window_changed()

    def eventFilter(self, watched, event) -> bool:
        if watched is self.view and event.type() == QtCore.QEvent.Type.Resize:
            self._place_closeup()
        return super().eventFilter(watched, event)

    def _set_text_size(self, scale: float, remember: bool = False) -> None:
        self.presentation.set_preferred(scale)
        for action in self.text_size_group.actions():
            action.setChecked(action.data() == scale)
        if remember:
            self.preferences.set_font_scale(scale)

    # -- help ------------------------------------------------------------------------

    def _set_help_topics(self) -> None:
        topics = {"model.html#energy": [self.readouts["energy"], self.readouts["drift"]],
                  "model.html#munthe-kaas": [self.readouts["orth"], self.panel.munthe_kaas],
                  "model.html#liftoff": [self.readouts["force"]],
                  "model.html#methods": [self.panel.methods.buttons()[0].parentWidget()],
                  "plots.html#energy": [self.plots.plots[0]],
                  "plots.html#orthogonality": [self.plots.plots[1]],
                  "plots.html#force": [self.plots.plots[2]],
                  "plots.html#colours": [self.view],
                  "plots.html#readouts": [self.readouts],
                  "compare.html#compare": [self.compare.panel, self.compare.error_plots],
                  "compare.html#summary": [self.compare.summary]}
        for topic, widgets in topics.items():
            for widget in widgets:
                helps.set_topic(widget, topic)

    def _all_actions(self) -> list[QtGui.QAction]:
        """The menus' actions in menu order, then the window's own (for the shortcuts page)."""
        def walk(menu):
            for action in menu.actions():
                yield from walk(action.menu()) if action.menu() else (action,)
        return [a for top in self.menuBar().actions() if top.menu() for a in walk(top.menu())] + self.actions()

    def show_help(self, topic: str) -> None:
        if self.help_window is None:
            self.help_window = helps.HelpWindow(self._all_actions, self)
            place_over(self.help_window, self)
        self.help_window.show_topic(topic)

    def context_help(self) -> None:
        """Help on the widget under the mouse (the model page if it has no topic)."""
        widget = QtWidgets.QApplication.widgetAt(QtGui.QCursor.pos())
        self.show_help(helps.topic_at(widget) or "model.html")

    # -- closing ---------------------------------------------------------------------

    def closeEvent(self, event: QtGui.QCloseEvent) -> None:
        if not self._may_discard():
            event.ignore()
            return
        self.modes.leave_all()   # the editing layout is what is remembered
        self.preferences.save(self)
        if self.speed_window is not None:
            self.speed_window.close()
        self.reset()  # stops the worker and lets go of the run's arrays
        self.controller.shutdown()
        self.stop_preparing()
        event.accept()


class StatusMessage(QtWidgets.QLabel):
    """The status bar's message, always two lines high (its tooltip holds all of a longer one):
    a message coming and going (as a slider is dragged) never resizes the 3-D view, which
    re-frames its camera on a resize (a second under software GL)."""

    def event(self, event) -> bool:
        if event.type() in (QtCore.QEvent.Type.FontChange, QtCore.QEvent.Type.Polish):
            self.setFixedHeight(2 * self.fontMetrics().lineSpacing())
        return super().event(event)

    def minimumSizeHint(self) -> QtCore.QSize:   # nor widens the window for a long message
        return QtCore.QSize(0, super().minimumSizeHint().height())


def _plain(text: str) -> str:
    """Text that a message box cannot take for rich text (it guesses from tags like <b>)."""
    return text.replace("<", "\u2039").replace(">", "\u203a") if QtGui.Qt.mightBeRichText(text) else text

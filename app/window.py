"""The main window: its layout (the Scene panel, the 3-D view with its time slider and
readouts, the plots), its actions, menus, toolbar and status bar, and the wiring between them.

What the actions do lives beside it: ``scene_files`` (open, save, revert, a scene shown),
``runs`` (start, pause, step, stop, reset, seek), ``drawing`` (the runs' moment shown),
``exports`` (CSV, PNG, MP4, GIF), ``compare_mode`` and ``modes`` (compare, presentation, the
panels), ``session`` (the widget-free document and undo history).
"""

from __future__ import annotations

import math
import sys

from PySide6 import QtCore, QtGui, QtWidgets

from rollball import Scene, __version__, resources
from rollball.examples import example_scenes

from . import help as helps
from .closeup import CloseUp
from .compare_mode import CompareMode
from .controller import RunController
from .drawing import Drawing
from .exports import Exports
from .inputs import UNDO_KEYS, ScenePanel
from .modes import DEFAULT_SIZE, Modes, fitted, place_over
from .plots import LivePlots
from .preferences import Preferences
from .presentation import TEXT_SIZES, Presentation
from .readouts import Readouts
from .runs import RunCommands
from .scene_files import SceneFiles
from .session import SceneSession
from .speed_window import SpeedWindow
from .start_editing import StartEditing
from .sweep_dialog import SweepDialog
from .timeline import TimeSlider
from .track_view import MeasuredTrack
from .view3d import SceneView
from .worker import finish_all

SLIDER_WIDTH = 240   # pixels of the time slider, at least, whatever the text beside it
SPEEDS = (("0.1×", 0.1), ("0.25×", 0.25), ("0.5×", 0.5), ("Real time", 1.0), ("2×", 2.0),
          ("5×", 5.0), ("10×", 10.0), ("As fast as computed", math.inf))


class MainWindow(QtWidgets.QMainWindow):
    def __init__(self, preferences: Preferences | None = None):
        super().__init__()
        self.preferences = preferences or Preferences()
        self.files = SceneFiles(self)          # open, save, revert; a scene shown
        self.session = SceneSession(self.files.show_scene, self)
        self.document = self.session.document
        self.undo_stack = self.session.undo
        self.landscape = None                  # the shown scene's, with its parameters' values
        self.controller = RunController(self)
        self.runs = RunCommands(self)          # start, pause, step, stop, reset, seek
        self.drawing = Drawing(self)           # the runs' moment shown
        self.exports = Exports(self)           # CSV, PNG, MP4 and GIF
        self.panel = ScenePanel()
        self.view = SceneView()
        self.closeup_frame = QtWidgets.QFrame(self.view, objectName="closeupFrame")
        self.closeup_frame.setStyleSheet("#closeupFrame { border: 2px solid #333; background: #333; }")
        self.closeup = CloseUp()
        frame_layout = QtWidgets.QVBoxLayout(self.closeup_frame)
        frame_layout.setContentsMargins(2, 2, 2, 2)
        frame_layout.addWidget(self.closeup)
        self.closeup_frame.hide()
        self.timeline = TimeSlider()
        self.plots = LivePlots()
        self.readouts = Readouts()
        self.speed_window: SpeedWindow | None = None   # made when first asked for
        self.start_editing = StartEditing(self.view, self.panel, self)   # the preview; the start dragged
        self.help_window: helps.HelpWindow | None = None
        self.measured = MeasuredTrack(self)    # File → Import Measured Track…, Analysis → Fit to Track…
        self._build_layout()
        self._build_actions()
        self._build_menus()
        self._build_toolbar()
        self._build_status()
        self.compare = CompareMode(self)
        self.presentation = Presentation(self)
        self.presentation.add_actions([self.scene_panel_action, self.plots_action, self.presentation_action])
        self.modes = Modes(self)
        self._wire()
        self.preferences.restore(self)
        self.modes.restored()   # the editing layout, whatever the last session showed
        self._set_text_size(self.preferences.font_scale())
        self._set_help_topics()
        self.runs.update_controls()

    def _wire(self) -> None:
        """What the parts say to each other."""
        controller, runs, drawing = self.controller, self.runs, self.drawing
        controller.stateChanged.connect(runs.state_changed)
        controller.frameReady.connect(drawing.draw)
        controller.event.connect(runs.run_event)
        controller.finished.connect(runs.finished)
        controller.failed.connect(lambda message: self._warn("The computation failed", message))
        self.panel.sceneChanged.connect(self.files.scene_edited)
        self.timeline.seeked.connect(runs.seek)
        self.undo_stack.cleanChanged.connect(lambda _clean: runs.update_controls())
        self.compare.panel.followChanged.connect(lambda _i: drawing.follow(self.follow_action.isChecked()))
        self.readouts.runsChanged.connect(self.presentation.fit_readouts)   # a row per run: their size again
        self.view.installEventFilter(self)   # keeps the close-up in the view's corner
        # the close-up out of the axes' way, after the paint that moved them
        self.view.axesPlaced.connect(drawing.place_closeup, QtCore.Qt.ConnectionType.QueuedConnection)

    # -- layout ----------------------------------------------------------------------

    def _build_layout(self) -> None:
        self.setWindowIcon(QtGui.QIcon(str(resources.path("icons", "rollball.svg"))))
        scroll = QtWidgets.QScrollArea(widgetResizable=True)
        scroll.setWidget(self.panel)
        scroll.setMinimumWidth(340)
        # large text: all of a row in reach
        scroll.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAsNeeded)
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
        # the events' links beside the slider give way (cut at the right) rather than widen the window
        # or squeeze the slider (large text in presentation left it a handle's width)
        self.timeline.events.setMinimumWidth(1)
        self.timeline.slider.setMinimumWidth(SLIDER_WIDTH)
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
        self.open_action = self._action("&Open Scene…", self.files.open_dialog, keys.Open, "Open a scene file")
        self.save_action = self._action("&Save Scene", self.files.save, keys.Save, "Save the scene")
        self.save_as_action = self._action("Save Scene &As…", self.files.save_as, keys.SaveAs,
                                           "Save the scene under a new name")
        self.export_action = self._action("&Export Trajectory CSV…", self.exports.export_dialog, "Ctrl+E",
                                          "Write the computed trajectory as CSV")
        self.image_action = self._action("Save &Image…", self.exports.save_image_dialog, "Ctrl+Shift+I",
                                         "Save the 3-D view as a PNG image (1×, 2×, 4×; caption; plots)")
        self.animation_action = self._action("Export &Animation…", self.exports.export_animation_dialog, "Ctrl+Shift+E",
                                             "Write the run's playback as an MP4 video or a GIF")
        self.revert_action = self._action("Re&vert Scene", self.files.revert, None,
                                          "Back to the scene as it was opened or last saved")
        self.undo_action = self.undo_stack.createUndoAction(self, "&Undo")
        self.undo_action.setShortcuts(UNDO_KEYS[:1])
        self.redo_action = self.undo_stack.createRedoAction(self, "&Redo")
        self.redo_action.setShortcuts(UNDO_KEYS[1:])
        self.undo_action.setStatusTip("Undo the last change of the scene's fields")
        self.redo_action.setStatusTip("Redo the change undone last")
        self.quit_action = self._action("&Quit", self.close, keys.Quit, "Quit RollBall")
        self.start_action = self._action("Start", self.runs.start, "F5", "Start the run from t = 0")
        self.pause_action = self._action("Pause", self.runs.toggle_pause, "Space", "Pause playback (again: resume)",
                                         name="pause")
        self.pause_action.setCheckable(True)   # held down while paused; Start says Resume meanwhile
        self.step_action = self._action("Step", self.runs.step_frame, "F6", "Advance one frame")
        self.stop_action = self._action("Stop", self.runs.stop, "Shift+F5", "Stop the computation here")
        self.reset_action = self._action("Reset", self.runs.reset, "Ctrl+R", "Back to t = 0")
        self.follow_action = self._action("&Follow Ball", self.drawing.follow, "F", "Camera follows the ball",
                                          checkable=True)
        self.camera_action = self._action("Reset &Camera", self.view.reset_camera, "C", "Default camera")
        self.back_action = self._action("Frame Back", lambda: self.controller.step(-1), "Left",
                                        "Show the moment one frame earlier")
        self.forward_action = self._action("Frame Forward", lambda: self.controller.step(1), "Right",
                                           "Show the moment one frame later")
        self.first_action = self._action("Go to Start", lambda: self.runs.seek(0.0), "Home", "Show t = 0")
        self.last_action = self._action("Go to End", lambda: self.runs.seek(math.inf), "End",
                                        "Show the last computed moment")
        self.liftoff_action = self._action("Go to &Lift-off", self.runs.go_to_liftoff, "L",
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
        self.plots_action = self._action("&Plots", lambda _on: self.modes.choose_folds(), "P",
                                         "Show the plots, or fold them away for a larger 3-D view", checkable=True)
        self.readouts_action = self._action("Rea&douts", lambda _on: self.modes.choose_folds(), None,
                                            "Show the readouts, or fold them away for a larger 3-D view",
                                            checkable=True)
        for shown in (self.plots_action, self.readouts_action):
            with QtCore.QSignalBlocker(shown):
                shown.setChecked(True)
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
                                        "A ring around the ball where it is drawn smaller than 6 % of the view's "
                                        "height (a mark to see it from afar; the ball inside is to scale)",
                                        checkable=True, name="ball_marker")
        self.mark_action.setChecked(True)
        self.future_action = self._action("Show &Future Events", self.drawing.show_future_events, None,
                                          "Mark every event of the run from the start (lift-offs, landings, "
                                          "slips, grips), not only those playback has reached", checkable=True)
        self.future_action.setChecked(self.drawing.show_future)
        self.timeline.set_show_future(self.drawing.show_future)
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
        self.recent_menu.aboutToShow.connect(lambda: self.files.fill_recent(self.recent_menu))
        self.examples_menu = files.addMenu("E&xamples")
        self.examples_menu.setToolTipsVisible(True)
        for path, scene in example_scenes():
            summary = scene.description if len(scene.description) <= 70 else scene.description[:67] + "…"
            action = self.examples_menu.addAction(f"{path.stem} — {summary}")
            action.setToolTip(scene.description)
            action.setStatusTip(scene.description)
            action.setData(str(path))
            action.triggered.connect(lambda _=False, p=path: self.files.open_scene(p, remember=False))
        files.addSeparator()
        files.addActions([self.save_action, self.save_as_action])
        files.addSeparator()
        files.addAction(self.revert_action)
        files.addSeparator()
        files.addActions([self.export_action, self.image_action, self.animation_action])
        files.addSeparator()
        files.addActions([self.measured.import_action, self.measured.close_action])
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
        view.addActions([self.follow_action, self.trail_action, self.mark_action, self.future_action,
                         self.camera_action])
        view.addSeparator()
        view.addActions([self.scene_panel_action, self.plots_action, self.readouts_action,
                         self.reset_layout_action])
        analysis = bar.addMenu("&Analysis")
        analysis.addActions([self.speed_error_action, self.sweep_action, self.measured.fit_action])
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

    # -- the scene, the analysis windows, messages -----------------------------------

    @property
    def scene(self) -> Scene | None:
        return self.panel.scene()

    def show_speed_against_error(self) -> None:
        """Compare every method on the current scene, in a window of its own."""
        self.panel.apply()
        if self.scene is None:
            return
        if self.speed_window is None:
            self.speed_window = SpeedWindow(self)
            self.speed_window.runChosen.connect(self.runs.load_run)
            place_over(self.speed_window, self)
        self.speed_window.compute(self.scene)

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
                                    f"<b>RollBall {__version__}</b><p>A solid ball rolling, sliding and flying over "
                                    f"z = f(x, y): fixed-step, implicit and adaptive methods, classic or "
                                    f"Munthe-Kaas.</p>")

    # -- modes, the window's own events, text size -------------------------------------

    def _compare_toggled(self, on: bool) -> None:
        if on != self.modes.compare:
            self.compare.set_active(on)
            self.modes.set_compare(on)

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
            self.drawing.place_closeup()
        return super().eventFilter(watched, event)

    def _set_text_size(self, scale: float, remember: bool = False) -> None:
        self.presentation.set_preferred(scale)
        if self.modes.presentation:
            self.modes.apply()   # what the 3-D view's share of the screen leaves room for, at this size
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
        if not self.files.may_discard():
            event.ignore()
            return
        self.modes.leave_all()   # the editing layout is what is remembered
        self.preferences.save(self)
        if self.speed_window is not None:
            self.speed_window.close()
        for dialog in self.findChildren(SweepDialog):
            dialog.close()   # its sweep is cancelled
        self.runs.reset()  # stops the worker and lets go of the run's arrays
        self.controller.shutdown()
        self.start_editing.shutdown()
        self.runs.stop_preparing()
        left = finish_all()   # every worker in flight cancelled and waited for, bounded
        if left:
            print(f"rollball-app: still at work when closing: {', '.join(left)}", file=sys.stderr)
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

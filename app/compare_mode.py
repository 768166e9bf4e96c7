"""Compare mode in the main window: the Compare dock (the runs, the summary), the true-error
plots in place of the live plots, and what starting, finishing and measuring do there.

The window keeps one of these (``window.compare``) and asks it; the runs themselves live in
the window's run controller like a single run.
"""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

from rollball import METHODS, Scene, Status

from . import compare_runs
from .budget import causes_on, floor_energy
from .contact_view import beyond_2011
from .compare_panel import ComparePanel
from .controller import Run
from .error_plots import ErrorPlots
from .summary import SummaryTable


class CompareMode:
    def __init__(self, window):
        self.window = w = window
        self.panel = ComparePanel()
        self.error_plots = ErrorPlots()
        self.summary = SummaryTable()
        self.panel.compareRequested.connect(w.runs.start)
        self.panel.runsChanged.connect(self._runs_edited)
        self.panel.shownChanged.connect(self.show_run)
        w.controller.measured.connect(self._measured)
        self.action = w.compare_action
        content = QtWidgets.QWidget()
        box = QtWidgets.QVBoxLayout(content)
        box.setContentsMargins(0, 0, 0, 0)
        box.addWidget(self.panel)
        box.addWidget(QtWidgets.QLabel(" Summary (hover the names for what they mean)"))
        box.addWidget(self.summary, 1)
        scroll = QtWidgets.QScrollArea(widgetResizable=True)   # large text: all of it in reach, the window
        scroll.setWidget(content)                               # no wider than the screen
        scroll.setFrameShape(QtWidgets.QFrame.Shape.NoFrame)
        scroll.setMinimumWidth(content.minimumSizeHint().width() + scroll.verticalScrollBar().sizeHint().width())
        self.dock = QtWidgets.QDockWidget("Compare", w, objectName="compareDock")
        self.dock.setWidget(scroll)
        self.dock.setFeatures(w.scene_dock.features())
        w.addDockWidget(QtCore.Qt.DockWidgetArea.LeftDockWidgetArea, self.dock)
        w.tabifyDockWidget(w.scene_dock, self.dock)
        self.dock.hide()
        w.bottom.addWidget(self.error_plots)

    @property
    def active(self) -> bool:
        return self.action.isChecked()

    @property
    def followed(self) -> int:
        """The run the camera follows (0 outside compare mode)."""
        return self.panel.followed if self.active and self.window.controller.runs else 0

    def enter(self, runs: list[compare_runs.CompareRun]) -> None:
        """Compare mode with these runs (``--compare`` on the command line)."""
        self.panel.set_runs(runs)
        self.action.setChecked(True)

    def set_active(self, on: bool) -> None:
        """Entering or leaving: the run so far is dropped (the window's ``Modes`` shows and
        hides the panels)."""
        w = self.window
        w.runs.reset()
        if on and not self.panel.rows and w.scene is not None:
            self.panel.use_preset(next(iter(compare_runs.PRESETS)))
        w.show_message("Compare mode: set the runs, then Compare (F5)" if on else "")

    def scene_changed(self, scene: Scene) -> None:
        self.panel.set_scene(scene)

    def start(self, scene: Scene) -> None:
        """Every run of the panel, and the reference, computed together. ValueError (and
        nothing started) when a run cannot be made."""
        w = self.window
        choices = self.panel.runs()
        if not choices:
            raise ValueError("add a run to compare (or choose a preset)")
        spacing = compare_runs.reference_spacing(choices, scene.duration)
        simulations = [compare_runs.simulation(scene, choice, spacing) for choice in choices]
        runs = [Run(sim, w.landscape, choice.label, color)
                for sim, choice, color in zip(simulations, choices, compare_runs.COLORS)]
        w.view.set_runs([run.color for run in runs])
        w.readouts.set_runs([(run.label, run.color) for run in runs])
        w.readouts.show_contact(beyond_2011(scene), columns=False)   # a row per run: slip and dissipation would not fit
        causes = causes_on(scene)
        self.error_plots.set_budget(causes, floor_energy(scene, w.landscape) if causes else 0.0)
        self.error_plots.set_runs(runs, scene.duration)
        self.summary.set_runs(runs)
        w.timeline.set_span(max(sim.t_end for sim in simulations))
        w.controller.start(runs, reference=(scene, scene.duration, spacing),
                           warm_ups=[compare_runs.warm_up(scene, choice) for choice in choices])
        for i, shown in enumerate(self.panel.shown()):
            self.show_run(i, shown)
        w.show_message(f"Comparing {len(runs)} runs to t = {scene.duration:g} s, with a reference run")

    def clear(self) -> None:
        """No results: the runs' summary and error curves go with the runs (a reset, another
        scene); the panel's choice of runs stays."""
        self.summary.set_runs([])
        self.error_plots.set_runs([], self.window.scene.duration if self.window.scene else 1.0)

    def finished(self) -> None:
        runs = self.window.controller.runs
        self.summary.fill()
        early = [f"{run.label} stopped early ({run.simulation.status.value.replace('_', ' ')})"
                 for run in runs if run.simulation.status is not Status.OK]
        waiting = "" if self.window.controller.reference else "; the reference is still being computed"
        self.window.show_message(f"Finished comparing {len(runs)} runs" + "".join(f"; {e}" for e in early)
                                 + waiting, warning=bool(early))

    def show_run(self, index: int, shown: bool) -> None:
        if self.active and index < len(self.window.controller.runs):
            self.window.view.set_run_visible(index, shown)
            self.error_plots.set_visible(index, shown)

    def _runs_edited(self) -> None:
        if self.active and self.window.controller.runs:
            self.window.runs.reset()   # the runs shown no longer are the ones set

    def _measured(self) -> None:
        """The reference is known: name it, and plot and tabulate every run's true error."""
        from rollball.comparison import REFERENCE_RTOL, reference_method

        controller = self.window.controller
        _, estimate = controller.reference
        self.error_plots.set_reference(f"{METHODS[reference_method()].label} at rtol {REFERENCE_RTOL:g}", estimate)
        self.error_plots.show_time(controller.play_time, self.followed)
        self.summary.fill()
        if controller.runs and all(run.ended for run in controller.runs):
            self.finished()   # the last word no longer says the reference is being computed

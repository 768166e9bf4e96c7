"""Compare mode's panel: the runs (method, Munthe-Kaas or classic, step or tolerance), their
colours, which are shown and which one the camera follows, and the presets."""

from __future__ import annotations

import math

from PySide6 import QtCore, QtWidgets

from rollball import METHODS, RunSpec, Scene

from .compare_runs import COLORS, MAX_RUNS, PRESETS, CompareRun, preset


class RunRow(QtWidgets.QWidget):
    """One run: colour, method, scheme, step or tolerance, shown, remove."""

    changed = QtCore.Signal()
    removed = QtCore.Signal(object)
    shownChanged = QtCore.Signal(object, bool)
    settingWanted = QtCore.Signal(object)     # the method's kind changed: give it a default setting

    def __init__(self, run: CompareRun, color: str, number: int, parent=None):
        super().__init__(parent)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.swatch = QtWidgets.QLabel("●")
        self.method = QtWidgets.QComboBox(objectName="run.method")
        for name, method in METHODS.items():
            self.method.addItem(method.label, name)
        self.munthe_kaas = QtWidgets.QCheckBox("MK", objectName="run.munthe_kaas")
        self.munthe_kaas.setToolTip("Munthe-Kaas (on) or the classic matrix update of R (off)")
        self.setting = QtWidgets.QLineEdit(objectName="run.setting")
        self.setting.setFixedWidth(70)
        self.shown = QtWidgets.QCheckBox(objectName="run.shown", checked=True)
        self.shown.setToolTip("Show this run's ball, trail and curves")
        remove = QtWidgets.QToolButton(text="✕", objectName="run.remove")
        remove.setToolTip("Remove this run")
        for widget in (self.swatch, self.method, self.munthe_kaas, self.setting, self.shown, remove):
            layout.addWidget(widget)
        layout.setStretch(1, 1)
        self.set_color(color, number)
        self.set_run(run)
        self.method.currentIndexChanged.connect(self._method_changed)
        self.munthe_kaas.toggled.connect(self.changed)
        self.setting.editingFinished.connect(self.changed)
        self.shown.toggled.connect(lambda on: self.shownChanged.emit(self, on))
        remove.clicked.connect(lambda: self.removed.emit(self))

    def set_color(self, color: str, number: int) -> None:
        self.swatch.setText(f"{number} ●")
        self.swatch.setStyleSheet(f"color: {color}; font-weight: bold;")

    def set_run(self, run: CompareRun) -> None:
        self.method.blockSignals(True)
        self.method.setCurrentIndex(self.method.findData(run.spec.method))
        self.method.blockSignals(False)
        self.munthe_kaas.setChecked(run.spec.munthe_kaas)
        self.setting.setText(repr(float(run.setting)))
        self._enable()

    def _enable(self) -> None:
        method = METHODS[self.method.currentData()]
        self.munthe_kaas.setEnabled(method.classic_allowed)
        if not method.classic_allowed:
            self.munthe_kaas.setChecked(True)
        self.setting.setToolTip("Step size h (s)" if method.fixed_step else "Relative tolerance rtol")

    def _method_changed(self) -> None:
        """A new method keeps the setting when it means the same (a step, or a tolerance), and
        takes the scene's own value when it does not."""
        before = self.setting.toolTip()
        self._enable()
        if self.setting.toolTip() != before:
            self.settingWanted.emit(self)
        self.changed.emit()

    def run(self) -> CompareRun:
        """The run this row describes; ValueError for a setting that is not a positive number."""
        spec = RunSpec(self.method.currentData(), self.munthe_kaas.isChecked())
        text = self.setting.text().strip()
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            what = "step size" if spec.fixed_step else "tolerance"
            raise ValueError(f"{spec}: the {what} must be a number greater than 0, not {text!r}")
        return CompareRun(spec, value)


class ComparePanel(QtWidgets.QWidget):
    """Up to ``MAX_RUNS`` runs of the current scene. ``runsChanged`` after any edit of the list;
    ``shownChanged(index, on)``; ``followChanged(index)``; ``compareRequested`` from its button."""

    runsChanged = QtCore.Signal()
    shownChanged = QtCore.Signal(int, bool)
    followChanged = QtCore.Signal(int)
    compareRequested = QtCore.Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.scene: Scene | None = None
        self.rows: list[RunRow] = []
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(6, 6, 6, 6)
        presets = QtWidgets.QHBoxLayout()
        presets.addWidget(QtWidgets.QLabel("Preset"))
        self.presets = QtWidgets.QComboBox(objectName="presets")
        self.presets.addItems(list(PRESETS))
        self.presets.setToolTip("Runs for a lesson; each takes the scene's step or tolerance")
        use = QtWidgets.QPushButton("Use", objectName="usePreset")
        use.clicked.connect(lambda: self.use_preset(self.presets.currentText()))
        presets.addWidget(self.presets, 1)
        presets.addWidget(use)
        layout.addLayout(presets)
        header = QtWidgets.QLabel("Method · Munthe-Kaas · step h or rtol · shown")
        header.setStyleSheet("color: #555;")
        layout.addWidget(header)
        self.row_box = QtWidgets.QVBoxLayout()
        layout.addLayout(self.row_box)
        buttons = QtWidgets.QHBoxLayout()
        self.add_button = QtWidgets.QPushButton("Add Run", objectName="addRun")
        self.add_button.clicked.connect(self.add_run)
        buttons.addWidget(self.add_button)
        buttons.addStretch(1)
        buttons.addWidget(QtWidgets.QLabel("Follow"))
        self.follow = QtWidgets.QComboBox(objectName="followRun")
        self.follow.setToolTip("The run the camera follows (View → Follow Ball)")
        self.follow.currentIndexChanged.connect(lambda i: i >= 0 and self.followChanged.emit(i))
        buttons.addWidget(self.follow)
        layout.addLayout(buttons)
        self.error = QtWidgets.QLabel(objectName="compareError", wordWrap=True)
        self.error.setStyleSheet("color: #b03a00;")
        layout.addWidget(self.error)
        self.compare_button = QtWidgets.QPushButton("Compare (F5)", objectName="compare")
        self.compare_button.clicked.connect(self.compareRequested)
        layout.addWidget(self.compare_button)

    def set_scene(self, scene: Scene) -> None:
        """The scene whose step and tolerance new runs take."""
        self.scene = scene

    def set_runs(self, runs: list[CompareRun]) -> None:
        for row in self.rows:
            self.row_box.removeWidget(row)
            row.deleteLater()
        self.rows = []
        for run in runs[:MAX_RUNS]:
            self._add_row(run)
        self._changed()

    def use_preset(self, name: str) -> None:
        self.set_runs(preset(name, self.scene))

    def add_run(self) -> None:
        """Another run: the scene's own method and step."""
        if len(self.rows) < MAX_RUNS and self.scene is not None:
            integrator = self.scene.integrator
            self._add_row(CompareRun.of(RunSpec(integrator.method, integrator.munthe_kaas
                                                or not METHODS[integrator.method].classic_allowed), self.scene))
            self._changed()

    def _add_row(self, run: CompareRun) -> None:
        row = RunRow(run, COLORS[len(self.rows)], len(self.rows) + 1)
        row.changed.connect(self._changed)
        row.removed.connect(self._remove)
        row.settingWanted.connect(self._default_setting)
        row.shownChanged.connect(lambda r, on: self.shownChanged.emit(self.rows.index(r), on))
        self.row_box.addWidget(row)
        self.rows.append(row)

    def _default_setting(self, row: RunRow) -> None:
        if self.scene is not None:
            row.setting.setText(repr(CompareRun.of(RunSpec(row.method.currentData()), self.scene).setting))

    def _remove(self, row: RunRow) -> None:
        self.rows.remove(row)
        self.row_box.removeWidget(row)
        row.deleteLater()
        for i, other in enumerate(self.rows):
            other.set_color(COLORS[i], i + 1)
        self._changed()

    def _changed(self) -> None:
        self.add_button.setEnabled(len(self.rows) < MAX_RUNS)
        self.follow.blockSignals(True)
        followed = max(0, self.follow.currentIndex())
        self.follow.clear()
        self.follow.addItems([f"{i + 1}" for i in range(len(self.rows))])
        self.follow.setCurrentIndex(min(followed, len(self.rows) - 1))
        self.follow.blockSignals(False)
        try:
            self.runs()
            self.error.setText("")
        except ValueError as error:
            self.error.setText(str(error))
        self.runsChanged.emit()

    def runs(self) -> list[CompareRun]:
        """The runs as set; ValueError naming the first field that is not valid."""
        return [row.run() for row in self.rows]

    def shown(self) -> list[bool]:
        return [row.shown.isChecked() for row in self.rows]

    @property
    def followed(self) -> int:
        return max(0, self.follow.currentIndex())

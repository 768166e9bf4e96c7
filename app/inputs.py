"""The input panel: every scene value as a field with its unit, validated as you type.

The fields are declared once (``NUMBER_FIELDS``); the panel turns them into a ``Scene`` through
the core's own validation, so the app accepts exactly what a scene file accepts. A field
that does not make a valid scene is marked, and explained right under it with the label the
user sees; the last valid scene stays current. When values are refused only together (Max
below Min), the field whose change broke the scene is the one marked.
"""

from __future__ import annotations

import re
import time

from PySide6 import QtCore, QtGui, QtWidgets

from rollball import FormulaError, Scene, SceneError
from rollball.formula import parameter_problem
from rollball.landscape import landscape_for
from rollball import METHODS, MethodKind

from . import contact_fields
from .contact_fields import ContactFields
from .field_row import ERROR_STYLE, field_row, message_label
from .parameters import ParameterRows
from .worker import Worker

# (dotted scene key, label, unit, tooltip), by group
# the Edit menu's Undo and Redo keys: in a field too they undo the scene's changes
UNDO_KEYS = [QtGui.QKeySequence(k) for k in ("Ctrl+Z", "Ctrl+Shift+Z", "Ctrl+Y")]
NUMBER_FIELDS = {
    "Ball": (
        ("ball.radius", "Radius", "m", "Radius r of the ball"),
        ("ball.mass", "Mass", "kg", "Mass m of the ball (homogeneous, inertia 2/5 m r²)"),
        ("gravity", "Gravity", "m/s²", "Gravitational acceleration g₀ (0 for none)"),
    ),
    "Start": (
        ("start.x", "x", "m", "Start contact point, x"),
        ("start.y", "y", "m", "Start contact point, y"),
        ("start.vx", "vx", "m/s", "Horizontal velocity of the centre, x component"),
        ("start.vy", "vy", "m/s", "Horizontal velocity of the centre, y component"),
        ("start.spin", "Spin", "rad/s", "Angular velocity about the surface normal"),
    ),
    "Integrator": (
        ("integrator.dt", "Step size", "s", "Time step h (adaptive: the first step tried)"),
        ("integrator.rtol", "Rel. tolerance", "", "Adaptive only: relative error allowed per step"),
        ("integrator.atol", "Abs. tolerance", "", "Adaptive only: absolute error allowed per step"),
        ("duration", "Duration", "s", "Simulated time to run"),
    ),
    "Grid": (
        ("view.min", "Min", "m", "The landscape is drawn on [min, max]² (smin)"),
        ("view.max", "Max", "m", "The landscape is drawn on [min, max]² (smax)"),
        ("view.step", "Spacing", "m", "Distance between grid lines"),
    ),
}
DEBOUNCE_MS = 250              # typing pause before a change is applied (a valid formula: none)
REDRAW_MS = 250                # while typing on: from a landscape drawn to the next (drawing one takes
                               # the GUI thread ~0.1 s, and keys must not wait for it)
METHODS_PER_LINE = 3           # method buttons per line of the panel
METHOD_KINDS = {MethodKind.FIXED: "explicit", MethodKind.ADAPTIVE: "adaptive, explicit",
                MethodKind.IMPLICIT: "implicit, symmetric"}


def _get(d: dict, key: str):
    for part in key.split("."):
        d = d[part]
    return d


def _set(d: dict, key: str, value) -> None:
    *path, last = key.split(".")
    for part in path:
        d = d[part]
    d[last] = value


def format_number(value: float) -> str:
    return repr(float(value))  # shortest text that reads back as the same number


LABELS = ({key: label for fields in NUMBER_FIELDS.values() for key, label, _, _ in fields} | {"landscape": "Formula"}
          | contact_fields.LABELS)
UNITS = {key: unit for fields in NUMBER_FIELDS.values() for key, _, unit, _ in fields} | contact_fields.UNITS
CHECKING = "checking…"
MAX_REASON = 160               # characters of a compiler's reason shown under the formula
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")                       # terminal colours
_PATH = re.compile(r"(?:[A-Za-z]:)?(?:[\\/][\w.~+-]+){2,}[\\/]?")   # an absolute file path
_NOISE = ("Failed in ", "During:", "File ", "There are ", "^", "- Of which", "Type Restricted")
CHECKING_STYLE = "color: #555;"
# how a mark looks: the field, its label in the form, the message under it
MARKS = {"error": ("QLineEdit { border: 2px solid #c0392b; background: #fdecea; }",
                   "color: #c0392b; font-weight: bold;", ERROR_STYLE),
         "notice": ("QLineEdit { border: 2px solid #d68910; }", "color: #b9770e; font-weight: bold;",
                    "color: #b9770e;")}
GRID_KEYS = ("start.x", "start.y", "view.min", "view.max")   # where the start is, against the grid


def labelled(text: str) -> str:
    """A core message with its dotted scene keys ("view.max") as the labels the user sees."""
    for key, label in LABELS.items():
        if "." in key:
            text = text.replace(key, label)
    return text


def _lookup(d: dict, key: str):
    """A dotted key's value, or None where the dictionary has none (start.omega left out)."""
    for part in key.split("."):
        if not isinstance(d, dict) or part not in d:
            return None
        d = d[part]
    return d


def _number(text: str) -> float:
    """A field's number; the minus sign of typeset text (U+2212) is a minus too."""
    return float(text.strip().replace("\u2212", "-"))


def compile_reason(error: Exception) -> str:
    """A compiler's refusal (numba's, over many lines, in terminal colours, naming the
    generated module in the cache folder) as one clean line for the formula's message: the
    missing function and the types it was given, or else the first line that says something,
    without colour codes or file paths."""
    text = _ANSI.sub("", str(error))
    called = re.search(r"function Function\(<built-in function (\w+)>\)", text)
    signature = re.search(r">>> *(.+)", text)
    if called and signature:
        reason = f"no version of {called.group(1)} takes {signature.group(1).strip().split('(', 1)[-1].rstrip(')')}"
    else:
        lines = [line.strip() for line in text.splitlines()]
        reason = next((line for line in lines if line and not line.startswith(_NOISE)), type(error).__name__)
    reason = _PATH.sub("…", reason).rstrip(":")
    return reason if len(reason) <= MAX_REASON else reason[: MAX_REASON - 1] + "…"


def _style(widget: QtWidgets.QWidget, sheet: str) -> None:
    """Set a style sheet when it differs (setting one re-polishes the widget, a few hundred µs
    each: every field on every keystroke would be milliseconds)."""
    if widget.styleSheet() != sheet:
        widget.setStyleSheet(sheet)


def check_formula(text: str, names: tuple[str, ...] = ()) -> str | None:
    """Why a formula is refused (parsed, differentiated and compiled: seconds at worst), or None."""
    try:
        landscape_for(text, names).compiled  # noqa: B018 - parse, differentiate and compile
    except FormulaError as error:
        return str(error)
    except Exception as error:  # e.g. numba refusing generated code
        return f"cannot compile the formula: {compile_reason(error)}"
    return None


class ScenePanel(QtWidgets.QWidget):
    """Fields for a scene. ``sceneChanged`` carries each new valid scene (after a typing pause).
    A field that keeps the fields from making a scene is ``marked`` (its key), with
    ``error_text`` shown right under it.

    A new formula is parsed, differentiated and compiled by a background ``Worker`` (that can take
    seconds), from the keystroke on, one text at a time, the newest next. A formula is applied as
    soon as the text in the field is known to be valid, without waiting for the typing pause (a
    text superseded by a key meanwhile is not applied); a refused text is marked only when the
    pause ends, so nothing is shown against a word half typed. If the pause ends before the
    check, the field says "checking…" meanwhile, the window stays responsive and the last valid
    scene stays current; ``checking`` is True until the result is in. While typing goes on, a
    landscape is drawn at most ``REDRAW_MS`` after the one before (the newest valid text then),
    so that keys do not wait for drawing. The scenes applied during one burst of typing (until
    the pause ends) are one undo step: ``gesture`` is the burst's.

    Undo and Redo keys (Ctrl+Z, Ctrl+Shift+Z, Ctrl+Y) in a field are the Edit menu's: they undo
    the scene's last change, not the field's text (which would be one more change).
    """

    sceneChanged = QtCore.Signal(object)

    def __init__(self, parent=None):
        super().__init__(parent)
        self._scene: Scene | None = None
        self._filling = False
        # (formula, parameter names) -> why it is refused (None: ready)
        self._checked: dict[tuple[str, tuple[str, ...]], str | None] = {}
        self._checking: tuple[str, tuple[str, ...]] | None = None   # being checked in the background
        self.gesture = None                        # while a change is applied: its drag or typing burst
        self._burst = 0                            # counts bursts of typing: one undo step each
        self.numbers: dict[str, QtWidgets.QLineEdit] = {}
        self.messages: dict[str, QtWidgets.QLabel] = {}      # under each field, by key
        self.row_labels: dict[str, QtWidgets.QLabel] = {}    # the form's label of each number field
        self._edits: list[str] = []                          # keys typed into, the latest last
        self.marked: str | None = None                       # the key of the field refused
        self.noticed: str | None = None                      # the key of a field with a notice
        self._timer = QtCore.QTimer(self, singleShot=True, interval=DEBOUNCE_MS)
        self._timer.timeout.connect(self.apply)
        self._redraw = QtCore.QTimer(self, singleShot=True)   # the next valid text typed, drawn
        self._redraw.timeout.connect(self._apply_typed_now)
        self._drawn_at = -float("inf")                        # when the last text typed was drawn
        self.contact = ContactFields(self)   # friction, restitution, after lift-off, start ω
        self.contact.edited.connect(self._edited)
        # every text field of the panel, those added later too, once it has the keyboard
        QtWidgets.QApplication.instance().focusChanged.connect(self._focused)

        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(6, 6, 6, 6)
        self.error = message_label("fieldError")   # a refusal that names no field of the panel
        layout.addWidget(self.error)
        layout.addWidget(self._landscape_group())
        for title, fields in NUMBER_FIELDS.items():
            group = QtWidgets.QGroupBox(title)
            form = QtWidgets.QFormLayout(group)
            form.setFieldGrowthPolicy(QtWidgets.QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
            if title == "Integrator":
                self._method_rows(form)
            for key, label, unit, tip in fields:
                self.row_labels[key] = QtWidgets.QLabel(label)
                form.addRow(self.row_labels[key], self._number_field(key, unit, tip))
            if title == "Integrator":
                form.addRow("Record", self._record_field())
            if title == "Start":
                self.contact.add_omega_row(form)
            layout.addWidget(group)
            if title == "Start":
                layout.addWidget(self.contact.group())
        layout.addStretch(1)

    def _focused(self, _old, new) -> None:
        if isinstance(new, QtWidgets.QLineEdit) and self.isAncestorOf(new):
            new.installEventFilter(self)   # (once: installing it again only moves it first)

    def eventFilter(self, watched, event) -> bool:
        """A field's Undo and Redo keys are left to the window's actions (the scene's undo)."""
        if event.type() == QtCore.QEvent.Type.ShortcutOverride and isinstance(watched, QtWidgets.QLineEdit) \
                and QtGui.QKeySequence(event.keyCombination()) in UNDO_KEYS:
            event.ignore()   # not taken by the field: the shortcut goes to the Edit menu's action
            return True
        return super().eventFilter(watched, event)

    # -- building ---------------------------------------------------------------------

    def _landscape_group(self) -> QtWidgets.QGroupBox:
        group = QtWidgets.QGroupBox("Landscape  z = f(x, y)  [m]")
        box = QtWidgets.QVBoxLayout(group)
        self.formula = QtWidgets.QLineEdit(objectName="formula", clearButtonEnabled=True)
        self.formula.setToolTip("x, y, pi, e, numbers, + - * / ^ and sin cos tan asin acos atan atan2 "
                                "sinh cosh tanh exp log sqrt abs min max …")
        self.formula.setPlaceholderText("e.g. 0.5*sin(x)*cos(y)")
        self.formula.textEdited.connect(lambda: self._edited("landscape"))
        self.formula_error = self.messages["landscape"] = message_label("formulaError")
        self.description = QtWidgets.QLineEdit(objectName="description")
        self.description.setPlaceholderText("Description (shown in the Examples menu)")
        self.description.textEdited.connect(lambda: self._edited())
        self.parameter_rows = ParameterRows()
        self.parameter_rows.edited.connect(lambda name: self._edited(f"parameters.{name}"))
        self.parameter_rows.dragged.connect(self._dragged)
        self.parameter_rows.changed.connect(self._parameters_changed)
        self.parameter_rows.propose = self._unknown_name
        box.addWidget(self.formula)
        box.addWidget(self.formula_error)
        box.addWidget(self.parameter_rows)
        box.addWidget(self.description)
        return group

    def _number_field(self, key: str, unit: str, tip: str) -> QtWidgets.QWidget:
        """The field with its unit beside it and its message (hidden while it is valid) under it."""
        edit = QtWidgets.QLineEdit(objectName=key)
        edit.setToolTip(tip)
        edit.textEdited.connect(lambda: self._edited(key))
        self.numbers[key] = edit
        row, self.messages[key] = field_row(edit, unit, key)
        return row

    def _method_rows(self, form: QtWidgets.QFormLayout) -> None:
        self.methods = QtWidgets.QButtonGroup(self)
        row = QtWidgets.QWidget()
        grid = QtWidgets.QGridLayout(row)  # a few per line: the panel stays narrow
        grid.setContentsMargins(0, 0, 0, 0)
        for i, (name, tableau) in enumerate(METHODS.items()):
            button = QtWidgets.QRadioButton(tableau.label, objectName=f"method.{name}")
            button.setToolTip(f"{tableau.label}: {METHOD_KINDS[tableau.kind]} Runge–Kutta of order {tableau.order}"
                              + (", step size chosen for the tolerances" if tableau.adaptive else ""))
            button.setProperty("method", name)
            self.methods.addButton(button)
            grid.addWidget(button, i // METHODS_PER_LINE, i % METHODS_PER_LINE)
        grid.setColumnStretch(METHODS_PER_LINE, 1)
        self.methods.buttonClicked.connect(self._method_clicked)
        form.addRow("Method", row)
        self.munthe_kaas = QtWidgets.QCheckBox("Munthe-Kaas (R stays a rotation)", objectName="munthe_kaas")
        self.munthe_kaas.setToolTip("Lie-group integration of the orientation. Off: R is integrated as a plain "
                                    "matrix, as in 2011, and the drawn ball deforms.")
        self.munthe_kaas.clicked.connect(lambda: self._edited())
        form.addRow("", self.munthe_kaas)

    def _method_clicked(self, *_):
        self._method_state()
        self._edited()

    def _method_state(self) -> None:
        """Adaptive: Munthe-Kaas always, tolerances instead of a recording stride."""
        method = METHODS[self.method()]
        adaptive = method.adaptive
        if not method.classic_allowed:
            self.munthe_kaas.setChecked(True)
        self.munthe_kaas.setEnabled(method.classic_allowed)
        for key in ("integrator.rtol", "integrator.atol"):
            self.numbers[key].setEnabled(adaptive)
        self.record_every.setEnabled(not adaptive)

    def _record_field(self) -> QtWidgets.QSpinBox:
        self.record_every = QtWidgets.QSpinBox(objectName="record_every", minimum=0, maximum=1_000_000)
        self.record_every.setSpecialValueText("auto")
        self.record_every.setPrefix("every ")
        self.record_every.setSuffix(" steps")
        self.record_every.setToolTip("Keep every N-th step for playback, plots and export (auto: every "
                                     "step up to 200,000 rows; adaptive runs keep 10,000 evenly spaced rows)")
        return self.record_every

    # -- scene <-> fields ------------------------------------------------------------

    def scene(self) -> Scene | None:
        """The last valid scene."""
        return self._scene

    def method(self) -> str:
        return self.methods.checkedButton().property("method")

    def set_scene(self, scene: Scene) -> None:
        """Show a scene in the fields (no ``sceneChanged``)."""
        self._timer.stop()
        self._redraw.stop()
        self._burst += 1
        self._scene = scene
        self._edits = []
        self._checked[(scene.landscape, scene.parameter_names)] = None  # a Scene's formula is valid
        data = scene.to_dict()
        self._filling = True
        try:
            self.formula.setText(scene.landscape)
            self.parameter_rows.set_parameters(scene.parameters)
            self.description.setText(scene.description)
            self.description.setCursorPosition(0)   # its beginning, not its end
            for key, edit in self.numbers.items():
                edit.setText(format_number(_get(data, key)))
            for button in self.methods.buttons():
                button.setChecked(button.property("method") == scene.integrator.method)
            self.munthe_kaas.setChecked(scene.integrator.munthe_kaas)
            self._method_state()
            self.contact.fill(scene)
        finally:
            self._filling = False
        self._show_notice(scene)

    def _edited(self, key: str | None = None) -> None:
        if self._filling:
            return
        if key is not None:
            self._edits = [k for k in self._edits if k != key] + [key]
        self._timer.start()
        if key == "landscape":
            now = (self._formula_text(), self.parameter_names())
            if now in self._checked:
                self._apply_typed()
            else:
                self._check_ahead()

    def _check_ahead(self) -> None:
        """Check the formula as typed in the background now, during the typing pause (nothing is
        shown meanwhile); a valid one is applied when its check is in."""
        now = (self._formula_text(), self.parameter_names())
        if self._checking is None and now not in self._checked:
            self._start_check(*now)

    def _apply_typed(self) -> None:
        """The text typed is valid: drawn once the GUI thread has had ``REDRAW_MS`` for keys
        since the last landscape drawn (at once after a pause), after the keys waiting."""
        if not self._redraw.isActive():
            wait = self._drawn_at + REDRAW_MS / 1e3 - time.monotonic()
            self._redraw.start(round(1e3 * max(0.0, wait)))

    def _apply_typed_now(self) -> None:
        """Mid-burst, the fields as typed, if they make a new valid scene with a formula known
        to be valid: applied now, as part of the burst's undo step. A refusal waits for the
        typing pause (the pause goes on)."""
        if self._checked.get((self._formula_text(), self.parameter_names()), "") is not None:
            return
        scene, _, _ = self.read()
        if scene is None or scene == self._scene:
            return
        self._show_notice(scene)
        self._scene = scene
        self.gesture = ("typing", self._burst)
        try:
            self.sceneChanged.emit(scene)
        finally:
            self.gesture = None
            self._drawn_at = time.monotonic()

    def _dragged(self, name: str) -> None:
        """A slider moved: applied at once (no typing pause), one undo step a drag."""
        if self._filling:
            return
        key = f"parameters.{name}"
        self._edits = [k for k in self._edits if k != key] + [key]
        self.gesture = ("slider", self.parameter_rows.gesture)
        try:
            self.apply()
        finally:
            self.gesture = None

    def put(self, values: dict[str, float], gesture) -> Scene | None:
        """Values set from outside the fields (the start dragged in the 3-D view): shown in
        their fields and applied at once; the changes of one ``gesture`` make one undo step."""
        for key, value in values.items():
            self.numbers[key].setText(format_number(value))
            self._edits = [k for k in self._edits if k != key] + [key]
        self.gesture = gesture
        try:
            return self.apply()
        finally:
            self.gesture = None

    def _parameters_changed(self, _name: str) -> None:
        """A parameter was added or removed: applied at once, the formula checked again with
        the new names (its text stays as typed, refused if it uses a name now gone)."""
        if not self._filling:
            self.apply()

    def _unknown_name(self) -> str:
        """The name the formula uses that no parameter has (what "Add Parameter…" proposes),
        or ""."""
        problem = self._checked.get((self._formula_text(), self.parameter_names()))
        found = re.match(r"unknown name '(\w+)'", problem or "")
        return found.group(1) if found and parameter_problem(found.group(1)) is None else ""

    def parameter_names(self) -> tuple[str, ...]:
        """The names the formula may use: the scene's parameters, as the panel shows them."""
        return tuple(self.parameter_rows.rows)

    @property
    def checking(self) -> bool:
        """A formula is being checked in the background."""
        return self._checking is not None

    def apply(self) -> Scene | None:
        """Validate the fields now; emit ``sceneChanged`` if they make a new valid scene. A
        formula not checked yet is checked in the background first (None meanwhile)."""
        self._timer.stop()
        self._redraw.stop()
        text = self._formula_text()
        if (text, self.parameter_names()) not in self._checked:
            self._check_formula(text)
            return None
        gesture = self.gesture if self.gesture is not None else ("typing", self._burst)
        self._burst += 1   # the burst ends here: the next key begins a new undo step
        scene, key, message = self.read()
        if scene is None:
            self._show_errors(key, message)
        else:
            self._show_notice(scene)
        if scene is not None and scene != self._scene:
            self._scene = scene
            self.gesture, outer = gesture, self.gesture
            try:
                self.sceneChanged.emit(scene)
            finally:
                self.gesture = outer
        return scene

    def _check_formula(self, text: str) -> None:
        self._show_errors(None, None)
        self.formula_error.setStyleSheet(CHECKING_STYLE)
        self.formula_error.setText(CHECKING)
        self.formula_error.show()
        if self._checking is None:  # one check at a time; the latest text follows it
            self._start_check(text, self.parameter_names())

    def _start_check(self, text: str, names: tuple[str, ...]) -> None:
        self._checking = (text, names)
        checking = self._checking
        worker = Worker(lambda _progress, _cancel: (checking, check_formula(*checking)), name="formula check")
        worker.done.connect(self._formula_done)   # to a method: dropped once the panel is gone
        worker.start()

    def _formula_done(self, result: tuple) -> None:
        self._formula_checked(*result)

    def _formula_checked(self, checked: tuple, problem: str | None) -> None:
        self._checked[checked] = problem
        self._checking = None
        now = (self._formula_text(), self.parameter_names())
        if self._timer.isActive():   # checked ahead, the typing pause still on
            if now == checked:
                self._apply_typed()   # valid: applied now; refused: marked when the pause ends
            else:
                self._check_ahead()   # superseded: the newest text next
        elif now == checked or now not in self._checked:
            self.apply()

    def _formula_text(self) -> str:
        return self.formula.text().strip()  # a space typed at either end changes nothing

    def read(self) -> tuple[Scene | None, str | None, str | None]:
        """(scene, None, None) from the fields, or (None, offending key, message)."""
        text, names = self._formula_text(), self.parameter_names()
        problem = self._checked.get((text, names))
        if problem is None and (text, names) not in self._checked:
            try:
                landscape_for(text, names)
            except FormulaError as error:
                problem = str(error)
        if problem is not None:
            return None, "landscape", problem
        data = (self._scene or Scene(landscape="0")).to_dict()
        data["landscape"] = text
        if names:
            data["parameters"], key, message = self.parameter_rows.specs()
            if key is not None:
                return None, key, message
        data["description"] = self.description.text()
        for key, edit in self.numbers.items():
            try:
                value = _number(edit.text())
            except ValueError:
                return None, key, f"{LABELS[key]}: " + ("not a number" if edit.text().strip() else "missing")
            _set(data, key, value)
        refused = self.contact.read(data)
        if refused is not None:
            return None, *refused
        data["integrator"]["method"] = self.method()
        data["integrator"]["munthe_kaas"] = self.munthe_kaas.isChecked()
        try:
            scene = Scene.from_dict(data)
        except SceneError as error:
            return None, *self._blame(data, error)
        return scene, None, None

    def _blame(self, data: dict, error: SceneError) -> tuple[str, str]:
        """(key, message) of the field to mark for a refused scene: the field typed into last
        whose new value alone breaks the last valid scene (Max = −5 under Min = −4 marks Max,
        though the core names Min), else the field the core names."""
        if self._scene is not None:
            valid = self._scene.to_dict()
            for key in reversed(self._edits):
                if ((key not in self.numbers and key not in self.contact.edits)
                        or _lookup(data, key) == _lookup(valid, key)):
                    continue
                alone = self._scene.to_dict()
                if _lookup(data, key) is None and key == contact_fields.OMEGA:
                    del alone["start"]["omega"]
                else:
                    _set(alone, key, _lookup(data, key))
                try:
                    Scene.from_dict(alone)
                except SceneError as refusal:
                    error = refusal
                    if refusal.key != key:   # refused together with a field left as it was
                        return key, self._together(key, refusal, alone)
                    break
        return error.key, f"{LABELS.get(error.key, error.key)}: {labelled(error.reason)}"

    @staticmethod
    def _together(key: str, error: SceneError, data: dict) -> str:
        """The message on ``key`` for a refusal the core gives to another field."""
        other, reason = error.key, labelled(error.reason)
        value = _lookup(data, other)
        if reason.startswith("must") and other in UNITS and isinstance(value, float):   # "Max: Min (−4 m) must be …"
            reason = f"{LABELS[other]} ({value:g} {UNITS[other]}".rstrip() + f") {reason}"
        return f"{LABELS[key]}: {reason}"

    def _show_notice(self, scene: Scene) -> None:
        """A valid scene whose start is outside the drawn grid: say so at the field changed
        last among those that place the start and the grid (the ball is drawn nowhere)."""
        s, v = scene.start, scene.view
        if v.min <= s.x <= v.max and v.min <= s.y <= v.max:
            self._show_errors(None, None)
            return
        recent = [key for key in self._edits if key in GRID_KEYS]
        key = recent[-1] if recent else "start.x" if not v.min <= s.x <= v.max else "start.y"
        self._show_errors(key, f"{LABELS[key]}: the start ({s.x:g}, {s.y:g}) m is outside the drawn grid, "
                               f"{v.min:g} to {v.max:g} m: the ball starts where no landscape is drawn",
                          mark="notice")

    def _show_errors(self, key: str | None, message: str | None, mark: str = "error") -> None:
        """Mark the field ``key`` (None: none) as refused (or with a notice) and show
        ``message`` right under it."""
        if key is not None and key.startswith("parameters."):   # parameters.a.value: the field of a
            key = ".".join(key.split(".")[:2])
        if key is not None and key.startswith(contact_fields.OMEGA):   # start.omega[1]: the ω field
            key = contact_fields.OMEGA
        self.marked, self.noticed = (key, None) if mark == "error" else (None, key)
        field_style, label_style, message_style = MARKS[mark]
        rows = self.parameter_rows
        fields = {"landscape": self.formula, **self.numbers, **rows.edits, **self.contact.edits}
        for name, edit in fields.items():
            _style(edit, field_style if name == key else "")
        for name, label in {**self.row_labels, **rows.labels, **self.contact.labels}.items():
            _style(label, label_style if name == key else "")
        messages = self._all_messages()
        shown_at = messages.get(key, self.error) if key is not None else None
        for label in (*messages.values(), self.error):
            _style(label, message_style)
            label.setVisible(label is shown_at)
        if key == "landscape":
            message = f"{message} — the last valid landscape is still shown"
        if shown_at is not None:
            shown_at.setText(message)
            QtCore.QTimer.singleShot(0, self, lambda: self._scroll_to(shown_at))   # once laid out

    def _scroll_to(self, label: QtWidgets.QLabel) -> None:
        """The message in sight, when the panel is in a scroll area."""
        parent = self.parentWidget()
        while parent is not None and not isinstance(parent, QtWidgets.QScrollArea):
            parent = parent.parentWidget()
        if parent is not None:
            parent.ensureWidgetVisible(label, 0, 8)

    @property
    def notice_text(self) -> str:
        """The notice on a field of a valid scene (empty when there is none)."""
        return self._all_messages()[self.noticed].text() if self.noticed else ""

    def _all_messages(self) -> dict[str, QtWidgets.QLabel]:
        """The message under each field, the parameters' too, by key."""
        return {**self.messages, **self.parameter_rows.messages, **self.contact.messages}

    @property
    def error_text(self) -> str:
        """The message currently shown (empty when the fields are valid)."""
        if self.noticed:
            return ""
        for label in (*self._all_messages().values(), self.error):
            if not label.isHidden():
                return label.text()
        return ""

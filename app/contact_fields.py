"""The scene panel's contact fields (scene version 3, docs/design.md §1): friction μ (empty:
always enough friction to roll, the 2011 model), restitution e, what the ball does after a
lift-off, and the start's angular velocity ω (empty: the rolling one); and what slows a ball
down (version 4): rolling resistance c_rr, spin friction μ_s, the air (density ρ and drag
coefficient C_d, both or neither, with a choice that fills both: none, or air at sea level
around a smooth ball) and whether a run ends where the ball comes to rest.

Declared once as data (``FIELDS``); the panel (``inputs.ScenePanel``) reads them into the
scene's dictionary and lets the core's validation judge them, as it does every other field.
"""

from __future__ import annotations

import re

from PySide6 import QtCore, QtWidgets

from rollball import Scene

from .field_row import field_row
from .help import set_topic

FRICTION, RESTITUTION, AFTER_LIFTOFF, OMEGA = ("contact.friction", "contact.restitution",
                                                "contact.after_liftoff", "start.omega")
ROLLING, SPIN, DENSITY, DRAG = ("contact.rolling_resistance", "contact.spin_friction", "air.density",
                                "air.drag_coefficient")
AIR, STOP_AT_REST = "air", "stop_at_rest"   # the air's choice (fills DENSITY and DRAG), the check box
# (dotted scene key, label, unit, placeholder shown while empty, tooltip)
FIELDS = (
    (FRICTION, "Friction μ", "", "empty: always rolls (2011)",
     "Coulomb's friction coefficient μ ≥ 0: the ball rolls while the friction force rolling needs is at most "
     "μ·F·N, else it slides. Empty: always enough friction to roll (the 2011 model)."),
    (RESTITUTION, "Restitution e", "", "",
     "0 to 1: the share of its normal speed a landing ball keeps when it bounces (0: no bounce)"),
    (OMEGA, "Start ω", "rad/s", "empty: rolling",
     "The initial angular velocity wx, wy, wz (world frame). Empty: the ball starts rolling "
     "(ω = N × v / r + spin·N). Needs a friction coefficient unless it rolls; the spin must then be 0."),
    (ROLLING, "Rolling resist.", "", "",
     "The rolling-resistance coefficient c_rr ≥ 0: a couple c_rr·r·F·N against the rolling, so a ball on a "
     "plane slows down at (5/7)·c_rr·g and stops; on a slope it stays at rest where tan θ ≤ c_rr. 0: none"),
    (SPIN, "Spin friction", "", "",
     "The spin-friction coefficient μ_s ≥ 0: a couple μ_s·r·F·N against the spin about the normal, which "
     "then falls at (5/2)·μ_s·g/r. 0: none"),
    (DENSITY, "Air density ρ", "kg/m³", "",
     "The air's density ρ ≥ 0 (air at sea level: 1.2 kg/m³): a drag force ½·ρ·C_d·π·r²·|ċ|² against the "
     "centre's velocity, in flight too. 0 (with C_d 0): no air"),
    (DRAG, "Drag coeff. C_d", "", "",
     "The drag coefficient C_d ≥ 0 (a smooth sphere: about 0.47); given with the density, or both 0"),
)
# The air's choice: (text, density, drag coefficient) filled into both fields; other values: "as typed"
AIR_CHOICES = (("none", 0.0, 0.0), ("air, smooth ball", 1.2, 0.47))
AIR_TYPED = "as typed below"
AIR_TIP = ("Air drag: none, or air at sea level (ρ = 1.2 kg/m³) around a smooth ball (C_d = 0.47); "
           "fills the two fields below, which take any other values")
STOP_AT_REST_TEXT = "end the run there"
STOP_AT_REST_TIP = ("Where the speed and the spin reach 0 and rolling resistance and friction can hold the ball "
                    "(on a slope: tan θ ≤ c_rr and tan θ ≤ μ), the run ends there. Off: it goes on to its "
                    "duration, the ball resting")
AFTER_LIFTOFF_CHOICES = (("fly", "flies, lands again"), ("glued", "stays on the surface (2011)"))
AFTER_LIFTOFF_TIP = ("Where the surface would have to pull the ball (lift-off): it flies the exact parabola and "
                     "lands with an impact, or it stays glued to the surface as in 2011 (lift-off reported, "
                     "what follows not physical)")
HELP_TOPIC = "model.html#contact"
SLOWING_TOPIC = "plots.html#budget"   # what slows the ball down, and where its energy goes
SLOWING = (ROLLING, SPIN, AIR, DENSITY, DRAG, STOP_AT_REST)
LABELS = {key: label for key, label, *_ in FIELDS} | {AFTER_LIFTOFF: "After lift-off", AIR: "Air",
                                                     STOP_AT_REST: "At rest"}
UNITS = {key: unit for key, _, unit, *_ in FIELDS}
KEYS = (FRICTION, RESTITUTION, AFTER_LIFTOFF, OMEGA, ROLLING, SPIN, AIR, DENSITY, DRAG, STOP_AT_REST)
NUMBERS = (FRICTION, RESTITUTION, OMEGA, ROLLING, SPIN, DENSITY, DRAG)   # the fields read as numbers
_SEPARATOR = re.compile(r"[,;\s]+")


def _number(text: str) -> float:
    return float(text.strip().replace("\u2212", "-"))   # a typeset minus is a minus too


def format_number(value: float) -> str:
    return repr(float(value))


def omega_text(omega) -> str:
    return "" if omega is None else ", ".join(format_number(w) for w in omega)


def parse(key: str, text: str):
    """A field's text as the scene's value: (value, None), or (None, the reason it is refused)."""
    text = text.strip()
    if key == OMEGA:
        if not text:
            return None, None
        parts = [p for p in _SEPARATOR.split(text) if p]
        try:
            values = [_number(p) for p in parts]
        except ValueError:
            values = []
        if len(values) != 3:
            return None, "three numbers wx, wy, wz (rad/s), or empty to start rolling"
        return values, None
    if not text:
        return (None, None) if key == FRICTION else (None, "missing")
    try:
        return _number(text), None
    except ValueError:
        return None, "not a number"


class ContactFields(QtCore.QObject):
    """The fields, their labels and messages (by key), built into forms the panel gives.
    ``edited(key)`` when the user changes one."""

    edited = QtCore.Signal(str)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.edits: dict[str, QtWidgets.QWidget] = {}
        self.labels: dict[str, QtWidgets.QLabel] = {}
        self.messages: dict[str, QtWidgets.QLabel] = {}

    # -- building ---------------------------------------------------------------------

    def _row(self, form: QtWidgets.QFormLayout, key: str, field: QtWidgets.QWidget, unit: str) -> None:
        row, self.messages[key] = field_row(field, unit, key)
        self.labels[key] = QtWidgets.QLabel(LABELS[key])
        self.edits[key] = field
        form.addRow(self.labels[key], row)
        for widget in (self.labels[key], row, field):   # F1 over a contact field: what it does
            set_topic(widget, SLOWING_TOPIC if key in SLOWING else HELP_TOPIC)

    def _edit(self, key: str) -> QtWidgets.QLineEdit:
        _, _, unit, placeholder, tip = next(f for f in FIELDS if f[0] == key)
        edit = QtWidgets.QLineEdit(objectName=key)
        edit.setPlaceholderText(placeholder)
        edit.setToolTip(tip)
        edit.textEdited.connect(lambda: self.edited.emit(key))
        return edit

    def add_omega_row(self, form: QtWidgets.QFormLayout) -> None:
        """The start's ω, in the Start group."""
        self._row(form, OMEGA, self._edit(OMEGA), UNITS[OMEGA])

    def group(self) -> QtWidgets.QGroupBox:
        """The Contact group: friction, restitution, after lift-off, rolling resistance, spin
        friction, the air and whether a run stops at rest."""
        box = QtWidgets.QGroupBox("Contact")
        set_topic(box, HELP_TOPIC)
        form = QtWidgets.QFormLayout(box)
        form.setFieldGrowthPolicy(QtWidgets.QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
        for key in (FRICTION, RESTITUTION):
            self._row(form, key, self._edit(key), UNITS[key])
        self.after_liftoff = QtWidgets.QComboBox(objectName=AFTER_LIFTOFF)
        for value, text in AFTER_LIFTOFF_CHOICES:
            self.after_liftoff.addItem(text, value)
        self.after_liftoff.setToolTip(AFTER_LIFTOFF_TIP)
        self.after_liftoff.activated.connect(lambda _i: self.edited.emit(AFTER_LIFTOFF))   # the user's choice only
        self._row(form, AFTER_LIFTOFF, self.after_liftoff, "")
        for key in (ROLLING, SPIN):
            self._row(form, key, self._edit(key), UNITS[key])
        self.air = QtWidgets.QComboBox(objectName=AIR)
        for text, density, drag in AIR_CHOICES:
            self.air.addItem(text, (density, drag))
        self.air.addItem(AIR_TYPED, None)
        self.air.setToolTip(AIR_TIP)
        self.air.setSizeAdjustPolicy(QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.air.setMinimumContentsLength(len(AIR_TYPED))   # the panel no wider than its other fields
        self.air.activated.connect(self._air_chosen)
        self._row(form, AIR, self.air, "")
        for key in (DENSITY, DRAG):
            self._row(form, key, self._edit(key), UNITS[key])
            self.edits[key].textEdited.connect(self._show_air)
        self.stop_at_rest = QtWidgets.QCheckBox(STOP_AT_REST_TEXT, objectName=STOP_AT_REST)
        self.stop_at_rest.setToolTip(STOP_AT_REST_TIP)
        self.stop_at_rest.clicked.connect(lambda _on: self.edited.emit(STOP_AT_REST))
        self._row(form, STOP_AT_REST, self.stop_at_rest, "")
        return box

    def _air_chosen(self, index: int) -> None:
        """A choice of air fills the density and the drag coefficient (as typed: left as they are)."""
        values = self.air.itemData(index)
        if values is None:
            return
        for key, value in zip((DENSITY, DRAG), values):
            self.edits[key].setText(format_number(value))
        self.edited.emit(DENSITY)
        self.edited.emit(DRAG)

    def _show_air(self) -> None:
        """The air's choice that the two fields hold (or "as typed")."""
        try:
            typed = (_number(self.text(DENSITY)), _number(self.text(DRAG)))
        except ValueError:
            typed = None
        found = next((i for i in range(self.air.count() - 1) if self.air.itemData(i) == typed), self.air.count() - 1)
        self.air.setCurrentIndex(found)

    # -- scene <-> fields ------------------------------------------------------------

    def fill(self, scene: Scene) -> None:
        """Show a scene's contact, air, stop at rest and start ω (no ``edited``)."""
        contact = scene.contact
        self.edits[FRICTION].setText("" if contact.friction is None else format_number(contact.friction))
        values = {RESTITUTION: contact.restitution, ROLLING: contact.rolling_resistance,
                  SPIN: contact.spin_friction, DENSITY: scene.air.density, DRAG: scene.air.drag_coefficient}
        for key, value in values.items():
            self.edits[key].setText(format_number(value))
        self.edits[OMEGA].setText(omega_text(scene.start.omega))
        self.after_liftoff.setCurrentIndex(self.after_liftoff.findData(contact.after_liftoff))
        self.stop_at_rest.setChecked(scene.stop_at_rest)
        self._show_air()

    def text(self, key: str) -> str:
        return self.edits[key].text()

    def read(self, data: dict) -> tuple[str, str] | None:
        """Put the fields' values into a scene's dictionary (``Scene.to_dict``'s); (key, message)
        of a field that holds no value of its kind (the core judges the rest)."""
        for key in NUMBERS:
            value, problem = parse(key, self.text(key))
            if problem is not None:
                return key, f"{LABELS[key]}: {problem}"
            group, name = key.split(".")
            holder = data.setdefault(group, {})
            if key == OMEGA and value is None:
                holder.pop("omega", None)
            else:
                holder[name] = value
        data["contact"]["after_liftoff"] = self.after_liftoff.currentData()
        data[STOP_AT_REST] = self.stop_at_rest.isChecked()
        return None

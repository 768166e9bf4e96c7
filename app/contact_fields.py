"""The scene panel's contact fields (scene version 3, docs/design.md §1): friction μ (empty:
always enough friction to roll, the 2011 model), restitution e, what the ball does after a
lift-off, and the start's angular velocity ω (empty: the rolling one).

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
)
AFTER_LIFTOFF_CHOICES = (("fly", "flies, lands again"), ("glued", "stays on the surface (2011)"))
AFTER_LIFTOFF_TIP = ("Where the surface would have to pull the ball (lift-off): it flies the exact parabola and "
                     "lands with an impact, or it stays glued to the surface as in 2011 (lift-off reported, "
                     "what follows not physical)")
HELP_TOPIC = "model.html#contact"
LABELS = {key: label for key, label, *_ in FIELDS} | {AFTER_LIFTOFF: "After lift-off"}
UNITS = {key: unit for key, _, unit, *_ in FIELDS}
KEYS = (FRICTION, RESTITUTION, AFTER_LIFTOFF, OMEGA)
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
        for widget in (self.labels[key], row, field):
            set_topic(widget, HELP_TOPIC)   # F1 over a contact field: what it does

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
        """The Contact group: friction, restitution, after lift-off."""
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
        return box

    # -- scene <-> fields ------------------------------------------------------------

    def fill(self, scene: Scene) -> None:
        """Show a scene's contact and start ω (no ``edited``)."""
        contact = scene.contact
        self.edits[FRICTION].setText("" if contact.friction is None else format_number(contact.friction))
        self.edits[RESTITUTION].setText(format_number(contact.restitution))
        self.edits[OMEGA].setText(omega_text(scene.start.omega))
        self.after_liftoff.setCurrentIndex(self.after_liftoff.findData(contact.after_liftoff))

    def text(self, key: str) -> str:
        return self.edits[key].text()

    def read(self, data: dict) -> tuple[str, str] | None:
        """Put the fields' values into a scene's dictionary (``Scene.to_dict``'s); (key, message)
        of a field that holds no value of its kind (the core judges the rest)."""
        contact = data.setdefault("contact", {})
        for key in (FRICTION, RESTITUTION, OMEGA):
            value, problem = parse(key, self.text(key))
            if problem is not None:
                return key, f"{LABELS[key]}: {problem}"
            group, name = key.split(".")
            holder = contact if group == "contact" else data["start"]
            if key == OMEGA and value is None:
                holder.pop("omega", None)
            else:
                holder[name] = value
        contact["after_liftoff"] = self.after_liftoff.currentData()
        return None

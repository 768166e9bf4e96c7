"""How to read a measured track's file: the questions File → Import Measured Track… asks after the
file is chosen (docs/design.md §10, "The track file").

A header may name its columns' units (``x (cm)``) or not, and a side view's camera calls the
scene's height ``y``: the dialog shows the file's first lines and asks which scene axes the
columns are, the units of columns whose header names none, and which point of the ball was
tracked. What it answers is ``TrackReading``, the arguments of ``rollball.Track.load``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from PySide6 import QtWidgets

from rollball.fit_options import LENGTH_UNITS, TIME_UNITS
from rollball.track import MAX_BYTES

PREVIEW_LINES = 6          # the file's first lines shown in the dialog
PREVIEW_BYTES = 4096       # read at most this much for them
# (what the user reads, Track.load's ``columns``)
MAPPINGS = (("As the header names them: t and x, y, z", None),
            ("Side view: the file's x, y are the scene's x, z (height)", {"x": "x", "z": "y"}))
POINTS = (("The ball's centre", "center"), ("Its contact point (on the surface)", "contact"))


@dataclass(frozen=True)
class TrackReading:
    """How a track file is read: ``Track.load``'s options and the point of the ball it follows."""

    columns: dict | None = None
    length_unit: str | None = None
    time_unit: str | None = None
    point: str = "center"


def first_lines(path: Path) -> str:
    """The file's first lines as text (what does not decode shown as �), or why it cannot be read."""
    try:
        with open(path, "rb") as stream:
            head = stream.read(PREVIEW_BYTES)
    except OSError as error:
        return f"({error.strerror or error})"
    return "\n".join(head.decode("utf-8", errors="replace").splitlines()[:PREVIEW_LINES])


class TrackImportDialog(QtWidgets.QDialog):
    """The file's first lines, then: which axes its columns are, the units where its header
    names none, the point of the ball tracked. ``reading()`` is the answer."""

    def __init__(self, path: Path, parent=None):
        super().__init__(parent)
        self.setWindowTitle(f"Import Measured Track — {path.name}")
        self.setObjectName("trackImportDialog")
        preview = QtWidgets.QPlainTextEdit(first_lines(path), objectName="preview", readOnly=True)
        preview.setLineWrapMode(QtWidgets.QPlainTextEdit.LineWrapMode.NoWrap)
        preview.setMaximumHeight(preview.fontMetrics().lineSpacing() * (PREVIEW_LINES + 2))
        self.mapping = self._combo("mapping", MAPPINGS)
        self.length_unit = self._combo("lengthUnit", [(u, u) for u in LENGTH_UNITS])
        self.time_unit = self._combo("timeUnit", [(u, u) for u in TIME_UNITS])
        for combo in (self.length_unit, self.time_unit):
            combo.setToolTip("The unit of the columns whose header names none (x, not x (cm)); a header "
                             "naming another unit than one chosen here is refused")
        self.point = self._combo("point", POINTS)
        self.mapping.setToolTip("Positions are in the scene's frame; a camera looking at the ball from the "
                                "side calls the scene's height y")
        self.point.setToolTip("What the tracking followed: the ball's centre (most video tracking) or the "
                              "point where it touches the surface")
        form = QtWidgets.QFormLayout()
        form.addRow("Columns", self.mapping)
        form.addRow("Lengths without a unit", self.length_unit)
        form.addRow("Times without a unit", self.time_unit)
        form.addRow("Tracked", self.point)
        note = QtWidgets.QLabel(f"CSV or TSV with a header naming t and two or three of x, y, z, units as "
                                f"x (cm); Tracker's export too; at most {MAX_BYTES // 1_000_000} MB.",
                                wordWrap=True)
        note.setStyleSheet("color: #555;")
        buttons = QtWidgets.QDialogButtonBox(QtWidgets.QDialogButtonBox.StandardButton.Ok
                                             | QtWidgets.QDialogButtonBox.StandardButton.Cancel)
        buttons.button(QtWidgets.QDialogButtonBox.StandardButton.Ok).setText("Import")
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addWidget(QtWidgets.QLabel("The file begins:"))
        layout.addWidget(preview)
        layout.addLayout(form)
        layout.addWidget(note)
        layout.addWidget(buttons)

    def _combo(self, name: str, choices) -> QtWidgets.QComboBox:
        combo = QtWidgets.QComboBox(objectName=name)
        for text, data in choices:
            combo.addItem(text, data)
        return combo

    def reading(self) -> TrackReading:
        """The answer. A unit is given to ``Track.load`` only where it is not the default (metres,
        seconds), so that a header naming another unit is not contradicted by the default."""
        length, time = self.length_unit.currentData(), self.time_unit.currentData()
        return TrackReading(self.mapping.currentData(), None if length == "m" else length,
                            None if time == "s" else time, self.point.currentData())

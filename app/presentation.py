"""Presentation mode for a lecture hall, and the text size that is also a preference.

Full screen; the scene panel collapsed into a slim bar at the left (its button opens the panel
again); readouts, status, time and plot axes at ``PRESENTATION_SCALE`` times the preferred text
size; a thicker trail; the close-up of the ball in the corner of the view. Leaving puts back
exactly what was there.
"""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

PRESENTATION_SCALE = 2.0      # times the preferred text size
TRAIL_WIDTH = 3.0             # pixels; times the scale in presentation mode
TEXT_SIZES = (("Normal", 1.0), ("Large (125 %)", 1.25), ("Larger (150 %)", 1.5), ("Largest (200 %)", 2.0))


def label_style(points: float) -> str:
    """A style sheet giving every label under a widget this font size (children's own colour
    or weight rules stay; new labels, e.g. rows added for more runs, get it too)."""
    return f"QLabel {{ font-size: {points:.1f}pt; }}"


class Presentation:
    """Applies a text scale to the window's readable parts, and enters or leaves presentation."""

    def __init__(self, window):
        self.window = window
        self.active = False
        self.preferred = 1.0            # the preference, used outside presentation
        self._restore = None
        self.bar = QtWidgets.QToolBar("Presentation", window, objectName="presentationBar")
        self.bar.setMovable(False)
        self.bar.setOrientation(QtCore.Qt.Orientation.Vertical)
        self.bar.setToolButtonStyle(QtCore.Qt.ToolButtonStyle.ToolButtonTextUnderIcon)
        window.addToolBar(QtCore.Qt.ToolBarArea.LeftToolBarArea, self.bar)
        self.bar.hide()

    @property
    def scale(self) -> float:
        return self.preferred * (PRESENTATION_SCALE if self.active else 1.0)

    def base_points(self) -> float:
        return QtWidgets.QApplication.font().pointSizeF()

    def apply_scale(self) -> None:
        w, scale = self.window, self.scale
        points = self.base_points() * scale
        for widget in (w.readouts, w.statusBar(), w.timeline):
            widget.setStyleSheet(label_style(points) if scale != 1.0 else "")
        w.state_label.setFixedWidth(round(150 * scale))
        w.timeline.label.setMinimumWidth(round(150 * scale))
        w.plots.set_font_scale(scale)
        w.view.trail.setData(width=TRAIL_WIDTH * (PRESENTATION_SCALE if self.active else 1.0))

    def set_preferred(self, scale: float) -> None:
        self.preferred = scale
        self.apply_scale()

    def set_active(self, on: bool) -> None:
        w = self.window
        if on == self.active:
            return
        dock = w.scene_dock
        if on:
            self._restore = (w.windowState(), dock.isVisible(), w.closeup_action.isChecked())
            dock.hide()
            self.bar.show()
            w.closeup_action.setChecked(True)
            w.showFullScreen()
        else:
            state, dock_visible, closeup = self._restore
            self.bar.hide()
            dock.setVisible(dock_visible)
            w.closeup_action.setChecked(closeup)
            w.setWindowState(state)
            if not state & QtCore.Qt.WindowState.WindowFullScreen:
                w.showNormal() if not state & QtCore.Qt.WindowState.WindowMaximized else w.showMaximized()
        self.active = on
        self.apply_scale()

"""Presentation mode for a lecture hall, and the text size that is also a preference.

Full screen; no side panels (the slim Presentation bar's Scene button opens the Scene panel for a
moment); readouts, status, time and the axes of every plot at ``PRESENTATION_SCALE`` times the
preferred text size, the readouts as large as the screen's width lets them be; a thicker trail;
the close-up of the ball in the corner of the view. ``app.modes`` enters and leaves it and puts
back exactly what was there; this module owns the bar and the text sizes.

The preferred text size (View → Text Size) applies everywhere, in and out of presentation:
readouts, status, time, plots, the Scene and Compare panels' fields, and the 3-D view's labels.
"""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

PRESENTATION_SCALE = 2.0      # times the preferred text size
# the 3-D view's least height (the close-up is in it); the smaller in presentation and at a larger text
# size, where the readouts' lines and the plots' text take more of a small screen's height
VIEW_HEIGHT, SMALL_VIEW_HEIGHT = 280, 200
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
        # the Scene and Leave buttons, at the end of the run toolbar: no row or column of their own
        self.bar = QtWidgets.QWidget(objectName="presentationBar")
        self.bar_layout = QtWidgets.QHBoxLayout(self.bar)
        self.bar_layout.setContentsMargins(6, 0, 0, 0)
        self.bar_action = window.run_toolbar.addWidget(self.bar)
        self.bar_action.setVisible(False)

    def add_actions(self, actions) -> None:
        for action in actions:
            button = QtWidgets.QToolButton(self.bar)
            button.setDefaultAction(action)
            button.setToolButtonStyle(QtCore.Qt.ToolButtonStyle.ToolButtonTextOnly)
            self.bar_layout.addWidget(button)

    def set_bar_visible(self, on: bool) -> None:
        self.bar_action.setVisible(on)

    @property
    def scale(self) -> float:
        return self.preferred * (PRESENTATION_SCALE if self.active else 1.0)

    def base_points(self) -> float:
        return QtWidgets.QApplication.font().pointSizeF()

    def apply_scale(self) -> None:
        w, scale = self.window, self.scale
        points = self.base_points() * scale
        for widget in (w.statusBar(), w.timeline):
            widget.setStyleSheet(label_style(points) if scale != 1.0 else "")
        self._fit_readouts(points)
        w.state_label.setFixedWidth(round(150 * min(scale, 1.5 * self.preferred)))
        w.timeline.label.setMinimumWidth(round(150 * scale))
        w.plots.set_font_scale(scale)
        w.compare.error_plots.set_font_scale(scale)
        w.view.set_label_scale(scale)
        panel_font = QtWidgets.QApplication.font()
        panel_font.setPointSizeF(self.base_points() * self.preferred)   # fields: the preference only
        for dock in (w.scene_dock, w.compare.dock):
            dock.widget().setFont(panel_font)
        w.view.trail.setData(width=TRAIL_WIDTH * (PRESENTATION_SCALE if self.active else 1.0))
        w.view.setMinimumHeight(SMALL_VIEW_HEIGHT if scale != 1.0 else VIEW_HEIGHT)
        # the run buttons as icons in presentation: the toolbar keeps the Scene and Leave
        # buttons on a 1024-pixel screen (their names are in their tooltips)
        w.run_toolbar.setToolButtonStyle(QtCore.Qt.ToolButtonStyle.ToolButtonIconOnly if self.active
                                         else QtCore.Qt.ToolButtonStyle.ToolButtonTextBesideIcon)

    def _fit_readouts(self, points: float) -> None:
        """The readouts at ``points``, or as large as the screen's width holds them."""
        readouts = self.window.readouts
        if points == self.base_points() or not self.active:   # outside presentation they wrap instead
            readouts.setStyleSheet(label_style(points) if points != self.base_points() else "")
            return
        screen = self.window.screen() or QtWidgets.QApplication.primaryScreen()
        room = screen.availableGeometry().width() - 24
        for _ in range(4):
            readouts.setStyleSheet(label_style(points))
            readouts.ensurePolished()
            for label in readouts.findChildren(QtWidgets.QLabel):
                label.ensurePolished()
            needed = readouts.one_line_width()
            if needed <= room or points <= self.base_points():
                return
            points = max(self.base_points(), points * room / needed * 0.98)

    def set_preferred(self, scale: float) -> None:
        self.preferred = scale
        self.apply_scale()

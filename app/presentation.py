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

from .modes import FRAME_ROOM

PRESENTATION_SCALE = 2.0      # times the preferred text size
# the 3-D view's least height (the close-up is in it); the smaller in presentation and at a larger text
# size, where the readouts' lines and the plots' text take more of a small screen's height
VIEW_HEIGHT, SMALL_VIEW_HEIGHT = 280, 200
LINE_SCALE = 3.0              # the status and time texts at most this many times the normal size (4 ×: the
                              # status's two lines would take a sixth of a 768-pixel screen)
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
        lines = min(scale, LINE_SCALE)   # the status's two lines and the time slider's row
        points = self.base_points() * lines
        for widget in (w.statusBar(), w.timeline):
            widget.setStyleSheet(label_style(points) if lines != 1.0 else "")
        self.fit_readouts()
        w.state_label.setFixedWidth(round(150 * min(lines, 1.5 * self.preferred)))
        w.timeline.label.setMinimumWidth(round(150 * lines))
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

    def fit_readouts(self) -> None:
        """The readouts at the text scale's size, or as large as the screen holds them: in
        presentation on one line across the screen's width; else, wrapped beside the side
        panels, within the height the rest of the window leaves on the screen."""
        w, readouts = self.window, self.window.readouts
        points = base = self.base_points()
        points *= self.scale
        screen = w.screen() or QtWidgets.QApplication.primaryScreen()
        area = screen.availableGeometry()
        for _ in range(8):
            readouts.setStyleSheet(label_style(points) if points != base else "")
            readouts.ensurePolished()
            for label in readouts.findChildren(QtWidgets.QLabel):
                label.ensurePolished()
            if points <= base:
                return
            if self.active:   # on one line: the size that fills the width
                needed, room = readouts.one_line_width(), area.width() - 24
                if needed <= room:
                    return
                points = max(base, points * room / needed * 0.98)
                continue
            docks = [d.minimumSizeHint().width() for d in (w.scene_dock, w.compare.dock)
                     if d.isVisibleTo(w) and not d.isFloating()]
            width = area.width() - FRAME_ROOM[0] - max(docks, default=0) - 24
            if self._height_beside_readouts() + readouts.height_for(width) <= area.height() - FRAME_ROOM[1]:
                return
            points = max(base, points * 0.9)   # (the height falls in steps, as the lines wrap)

    def _height_beside_readouts(self) -> int:
        """The least height of the window's parts above and below the readouts: menus, toolbar,
        status, time slider, the 3-D view and the plots (where shown), and what lies between."""
        w = self.window
        bars = sum(part.sizeHint().height() for part in (w.menuBar(), w.run_toolbar, w.statusBar()))
        plots = w.bottom.minimumSizeHint().height() + w.splitter.handleWidth() if w.bottom.isVisibleTo(w) else 0
        column = w.view.parentWidget().layout()
        return (bars + w.timeline.minimumSizeHint().height() + w.view.minimumHeight() + plots
                + column.spacing() * (column.count() - 1))

    def set_preferred(self, scale: float) -> None:
        self.preferred = scale
        self.apply_scale()

"""The window's modes in one place: what each shows, and what leaving it restores.

Two switches make the modes: **compare** (several runs side by side, the Compare panel, the
true-error plots) and **presentation** (full screen, large text, the close-up, no side panels).
Editing is neither; playback and scrubbing (the run controller's state and the time shown) go
on in any of them and are not changed by switching. ``layout`` says, without any widget, what
a combination shows; ``Modes`` applies it to the window and keeps what the user chose in the
editing layout (the Scene panel, the close-up, the window's place and size) so that leaving a
mode gives exactly that back.

The layout remembered between sessions is always the editing one: leaving the modes comes
before saving, and whatever was saved, the Scene panel is shown and the Compare panel hidden at
start (a layout can never hide the Scene panel).

The plots and the readouts can be folded away (View → Plots, View → Readouts). Presentation
folds what would leave the 3-D view less than ``VIEW_SHARE`` of the screen's height (a 1024×768
projector: the plots, in compare mode with many runs the readouts too); the bar's Plots button and
View → Readouts unfold them; leaving presentation gives back what the editing layout showed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from PySide6 import QtCore, QtGui, QtWidgets

DEFAULT_SIZE = (1280, 860)   # the window's size on a screen that has room for it
FRAME_ROOM = (8, 40)         # pixels of the available screen left for a window manager's frame
SETTLE_MS = 3000             # after leaving full screen, the window manager's moves are undone this long
RETRY_MS = 50                # meanwhile, a window that cannot yet be put back is tried again this often
ERROR_PLOTS_SHARE = 0.4      # of the view's and plots' height, at least, for compare mode's plots
PRESENTATION_PLOTS_SHARE = 0.47   # the same in presentation, where their text is larger
PLOTS_ENOUGH = 380           # pixels: the error plots need no more (a large screen's view takes the rest)
PRESENTATION_PLOTS_LEAST = 240   # pixels the error plots keep in presentation, where the 3-D view comes first
LIVE_PLOTS_LEAST = 160      # pixels the live plots need in presentation to be read
VIEW_SHARE = 0.6            # of the screen's height, at least, for the 3-D view in presentation: the
                            # readouts, then the plots, are folded away where they would leave it less


@dataclass(frozen=True)
class Shown:
    """What the window shows in a combination of modes."""
    scene_panel: bool       # the Scene panel (in compare mode: a tab behind the Compare panel)
    compare_panel: bool
    presentation_bar: bool  # the slim bar with the Scene button
    closeup: bool
    error_plots: bool       # compare mode's true-error plots, else the live plots
    full_screen: bool


def layout(compare: bool, presentation: bool, scene_wanted: bool = True, closeup_wanted: bool = False) -> Shown:
    """What shows, from the two switches and the user's choices for the editing layout."""
    if presentation:   # the view, its close-up, readouts and plots take the whole screen
        return Shown(scene_panel=False, compare_panel=False, presentation_bar=True, closeup=True,
                     error_plots=compare, full_screen=True)
    return Shown(scene_panel=scene_wanted or compare, compare_panel=compare, presentation_bar=False,
                 closeup=closeup_wanted, error_plots=compare, full_screen=False)


def fitted(size: tuple[int, int], available: QtCore.QRect) -> QtCore.QSize:
    """``size``, made smaller where the available screen has less room (a frame's room left)."""
    return QtCore.QSize(min(size[0], available.width() - FRAME_ROOM[0]),
                        min(size[1], available.height() - FRAME_ROOM[1]))


def clamp_to_screen(widget: QtWidgets.QWidget, screen: QtGui.QScreen | None = None) -> None:
    """Move and shrink a top-level window so that all of it is on its screen's available area."""
    screen = screen or widget.screen() or QtWidgets.QApplication.primaryScreen()
    if screen is None:
        return
    area = screen.availableGeometry()
    frame = widget.frameGeometry()
    extra_w, extra_h = frame.width() - widget.width(), frame.height() - widget.height()
    w = min(widget.width(), area.width() - extra_w)
    h = min(widget.height(), area.height() - extra_h)
    if (w, h) != (widget.width(), widget.height()):
        widget.resize(max(w, widget.minimumWidth()), max(h, widget.minimumHeight()))
        frame = widget.frameGeometry()
    x = min(max(frame.x(), area.left()), area.right() + 1 - frame.width())
    y = min(max(frame.y(), area.top()), area.bottom() + 1 - frame.height())
    if (x, y) != (frame.x(), frame.y()):
        widget.move(max(x, area.left()), max(y, area.top()))


def place_over(widget: QtWidgets.QWidget, owner: QtWidgets.QWidget) -> None:
    """A secondary window (help, speed against error, a sweep) at most as large as the owner's
    screen has room for, centred over the owner, and wholly on that screen."""
    screen = owner.screen() or QtWidgets.QApplication.primaryScreen()
    if screen is None:
        return
    area = screen.availableGeometry()
    size = fitted((widget.width(), widget.height()), area)
    widget.resize(size.expandedTo(widget.minimumSizeHint()).boundedTo(area.size()))
    center = owner.frameGeometry().center()
    widget.move(center.x() - widget.width() // 2, center.y() - widget.height() // 2)
    clamp_to_screen(widget, screen)


class Modes:
    """The window's modes, applied to it. The window's actions call ``set_compare``,
    ``set_presentation``, ``choose_scene_panel`` and ``choose_closeup``; nothing else shows or
    hides the docks, the bar or the close-up."""

    def __init__(self, window):
        self.window = window
        self.compare = False
        self.presentation = False
        self.scene_wanted = True      # the user's choices in the editing layout
        self.closeup_wanted = False
        self._normal_geometry: QtCore.QRect | None = None   # the window before presentation
        self._was_maximized = False
        self._settle_until = 0.0   # time.monotonic() until which leaving full screen settles
        self._normal_sizes: list[int] | None = None     # the view's and plots' heights before presentation
        self._applying = False
        self._editing_sizes: list[int] | None = None   # the view's and plots' heights when editing
        self._editing_folds: tuple[bool, bool] | None = None   # plots and readouts shown, before presentation
        self._folds_chosen = False    # in presentation: the user folded or unfolded them
        self.default_state = window.saveState()   # for View → Reset Layout

    def shown(self) -> Shown:
        return layout(self.compare, self.presentation, self.scene_wanted, self.closeup_wanted)

    # -- switches --------------------------------------------------------------------

    def set_compare(self, on: bool) -> None:
        if on == self.compare:
            return
        self.compare = on
        if self.presentation:   # leaving presentation gives back the heights of the mode it leaves to
            self._normal_sizes = None if on else self._editing_sizes
        self.apply(raise_compare=on)

    def set_presentation(self, on: bool) -> None:
        if on == self.presentation:
            return
        w = self.window
        if on:
            self._normal_geometry = QtCore.QRect(w.geometry())
            self._was_maximized = w.isMaximized()
            self._normal_sizes = w.splitter.sizes()
            self._editing_folds = (w.plots_action.isChecked(), w.readouts_action.isChecked())
            self._folds_chosen = False
        self.presentation = on
        w.presentation.active = on
        w.presentation.apply_scale()
        if not on and self._editing_folds is not None:
            self._set_folds(*self._editing_folds)
        if on:
            self._settle_until = 0.0
            self.apply(raise_compare=self.compare)
            w.showFullScreen()
            return
        # the small text's smaller minimum sizes first: a panel shown beside the large text's
        # minimum would widen the window
        QtWidgets.QApplication.sendPostedEvents(None, QtCore.QEvent.Type.LayoutRequest)
        w.showMaximized() if self._was_maximized else w.showNormal()
        self.apply(raise_compare=self.compare)
        if not self._was_maximized and self._normal_geometry is not None:
            # a window manager leaves full screen in its own time and may place and size the
            # window as it likes meanwhile: until it has settled, the window goes back to where it was
            self._settle_until = time.monotonic() + SETTLE_MS / 1000
            self._put_back()
            QtCore.QTimer.singleShot(SETTLE_MS // 3, self.window, self._put_back)

    def window_changed(self) -> None:
        """The window was resized, moved or changed state (the window's event hook)."""
        if self.presentation:
            self._share_height(self.shown())   # the plots' share of the full screen
        if time.monotonic() < self._settle_until:
            QtCore.QTimer.singleShot(0, self.window, self._put_back)

    def _put_back(self) -> None:
        w, rect = self.window, self._normal_geometry
        if self.presentation or w.isMaximized() or rect is None:
            return
        if w.windowState() & QtCore.Qt.WindowState.WindowFullScreen:
            w.showNormal()
        if w.geometry() != rect:
            w.setGeometry(rect)
        if w.geometry() != rect and time.monotonic() < self._settle_until:
            # the large text's minimum sizes are still in the layout (a plot's axis takes its
            # new width when it is next drawn): again as soon as they have gone
            QtCore.QTimer.singleShot(RETRY_MS, self.window, self._put_back)
        if w.geometry() == rect and self._normal_sizes and w.splitter.sizes() != self._normal_sizes:
            w.splitter.setSizes(self._normal_sizes)   # the view's and plots' heights as they were

    def choose_scene_panel(self, on: bool) -> None:
        """The Scene action: in presentation it opens or closes the panel over the view for a
        moment; otherwise it is the editing layout's choice."""
        if self._applying:
            return
        if self.presentation:
            self.window.scene_dock.setVisible(on)
            if on:
                self.window.scene_dock.raise_()
            return
        self.scene_wanted = on
        self.apply()

    def choose_closeup(self, on: bool) -> None:
        if self._applying:
            return
        if not self.presentation:
            self.closeup_wanted = on
        self.window.drawing.show_closeup(on)

    def choose_folds(self) -> None:
        """View → Plots or Readouts toggled: shown or folded away (in presentation, until it is left)."""
        if self._applying:
            return
        self._folds_chosen = self.presentation
        w = self.window
        self._set_folds(w.plots_action.isChecked(), w.readouts_action.isChecked())
        self._share_height(self.shown())

    def _set_folds(self, plots: bool, readouts: bool) -> None:
        w = self.window
        applying, self._applying = self._applying, True
        try:
            w.plots_action.setChecked(plots)
            w.readouts_action.setChecked(readouts)
        finally:
            self._applying = applying
        w.bottom.setVisible(plots)
        w.readouts.setVisible(readouts)

    def presentation_folds(self) -> tuple[bool, bool]:
        """Whether the plots and the readouts are shown in presentation: each only where the 3-D
        view keeps ``VIEW_SHARE`` of the screen's height (the readouts first, the plots after)."""
        w = self.window
        screen = w.screen() or QtWidgets.QApplication.primaryScreen()
        height = screen.geometry().height()
        for widget in (w.readouts, w.timeline, w.statusBar()):
            widget.ensurePolished()
        fixed = sum(part.sizeHint().height() for part in (w.menuBar(), w.run_toolbar, w.statusBar(), w.timeline))
        room = height - fixed - round(VIEW_SHARE * height)   # for the readouts and the plots
        w.readouts.fit_width(screen.geometry().width())   # as the full screen will lay them out
        readouts = w.readouts.minimumSizeHint().height()
        shown_readouts = readouts <= room
        room -= readouts if shown_readouts else 0
        least = PRESENTATION_PLOTS_LEAST if self.compare else LIVE_PLOTS_LEAST
        return least <= room, shown_readouts

    # -- applying --------------------------------------------------------------------

    def apply(self, raise_compare: bool = False) -> None:
        """Show and hide the window's parts as the modes say."""
        w, shown = self.window, self.shown()
        self._applying = True
        try:
            w.presentation.set_bar_visible(shown.presentation_bar)
            w.compare.dock.setVisible(shown.compare_panel)
            w.scene_dock.setVisible(shown.scene_panel)
            if shown.compare_panel and raise_compare:
                w.compare.dock.raise_()
            elif shown.scene_panel and not shown.compare_panel:
                w.scene_dock.raise_()
            w.scene_panel_action.setChecked(shown.scene_panel)
            w.closeup_action.setChecked(shown.closeup)
            w.drawing.show_closeup(shown.closeup)
            w.bottom.setCurrentWidget(w.compare.error_plots if shown.error_plots else w.plots)
            if self.presentation and not self._folds_chosen:
                self._set_folds(*self.presentation_folds())
            self._share_height(shown)
            w.compare_action.setChecked(self.compare)
            w.presentation_action.setChecked(self.presentation)
            w.leave_action.setEnabled(self.presentation)
        finally:
            self._applying = False

    def _share_height(self, shown: Shown) -> None:
        """The error plots get a good share of the height (three panels and a legend); back in
        editing, the heights the user had."""
        splitter = self.window.splitter
        sizes, total = splitter.sizes(), sum(splitter.sizes())
        editing = not (self.compare or self.presentation)
        if editing:
            if self._editing_sizes is not None:
                splitter.setSizes(self._editing_sizes)
                self._editing_sizes = None
            return
        if self._editing_sizes is None and total:
            self._editing_sizes = sizes
        share = PRESENTATION_PLOTS_SHARE if self.presentation else ERROR_PLOTS_SHARE
        below = min(round(share * total), PLOTS_ENOUGH)   # on a large screen the view takes the rest
        if self.presentation:
            # the 3-D view at least as tall as the plots (the balls seen from the back of the room; a
            # projector's 1024x768 left it 200 pixels), the plots keeping PRESENTATION_PLOTS_LEAST
            column = self.window.view.parentWidget().layout()   # the view, the time slider, the readouts
            beside = sum(column.itemAt(i).sizeHint().height() for i in range(column.count())
                         if column.itemAt(i).widget() is not self.window.view)
            beside += column.spacing() * (column.count() - 1)
            below = min(below, max(PRESENTATION_PLOTS_LEAST, (total - beside) // 2))
            screen = self.window.screen() or QtWidgets.QApplication.primaryScreen()
            view_least = round(VIEW_SHARE * screen.geometry().height())
            below = max(min(below, total - beside - view_least), LIVE_PLOTS_LEAST)
        if shown.error_plots and total and (sizes[1] < below or self.presentation and sizes[1] != below):
            splitter.setSizes([total - below, below])

    # -- what is remembered ----------------------------------------------------------

    def leave_all(self) -> None:
        """Back to the editing layout (before the layout is saved)."""
        self.set_presentation(False)
        if self.compare:
            self.window.compare_action.setChecked(False)

    def restored(self) -> None:
        """After a saved layout was restored: the editing layout, whatever was saved, on screen."""
        w = self.window
        if w.windowState() & QtCore.Qt.WindowState.WindowFullScreen:
            w.setWindowState(w.windowState() & ~QtCore.Qt.WindowState.WindowFullScreen)
        self.compare = self.presentation = False
        self.scene_wanted = True
        w.scene_dock.setFloating(False) if _off_screen(w.scene_dock) else None
        w.compare.dock.setFloating(False) if _off_screen(w.compare.dock) else None
        self.apply()
        if not w.isMaximized():
            clamp_to_screen(w)

    def reset_layout(self) -> None:
        """View → Reset Layout: the panels where they were at first, the window at its default
        size (fitted to the screen), the Scene panel shown."""
        w = self.window
        self.set_presentation(False)
        w.restoreState(self.default_state)
        self.scene_wanted = True
        self.closeup_wanted = False
        w.showNormal()
        screen = w.screen() or QtWidgets.QApplication.primaryScreen()
        w.resize(fitted(DEFAULT_SIZE, screen.availableGeometry()))
        clamp_to_screen(w)
        self._set_folds(True, True)
        self._editing_sizes = None
        total = sum(w.splitter.sizes())
        w.splitter.setSizes([total - total // 5, total // 5])   # the view 4 : the plots 1, as at first
        self.apply(raise_compare=self.compare)


def _off_screen(dock: QtWidgets.QDockWidget) -> bool:
    """A floating dock that no screen shows."""
    if not dock.isFloating():
        return False
    return QtGui.QGuiApplication.screenAt(dock.geometry().center()) is None

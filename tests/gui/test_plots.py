"""The live plots: log axes labelled legibly at powers of ten, whatever the data span and size;
plots that follow the ball while it plays."""

import time

import numpy as np
import pytest

from rollball_app import help as helps
from rollball_app.controller import PAUSED, RUNNING
from rollball_app.plots import FLOOR, LivePlots
from rollball_app.playback import ENERGY_ERROR, ORTHOGONALITY, RunBuffer
from rollball_app.drawing import PLOT_INTERVAL
from rollball.trajectory import T

from .guitools import assert_legible, exponent


class Rows(RunBuffer):
    """A run's buffer whose energy error follows given values (only the plotted columns)."""

    def __init__(self, energy_error: np.ndarray, orthogonality_error: np.ndarray):
        super().__init__(None, 1.0, 0.1, 9.81, capacity=len(energy_error))
        block = np.zeros((len(energy_error), self._data.shape[1]))
        block[:, T] = np.linspace(0.0, 10.0, len(energy_error))
        block[:, ENERGY_ERROR], block[:, ORTHOGONALITY] = energy_error, orthogonality_error
        self.append(block)


SPANS = [(-17, -17), (-16, -15.7), (-9, -8), (-9, -7.3), (-8.5, -6.2), (-12, -3), (-17, 0), (-3, 1),
         (-14.2, -14.1), (-2, -0.5), (-17, 2)]


# as in the default window, at 1024×700, and in presentation (full screen, text twice as large)
@pytest.mark.parametrize(("size", "scale"), [((900, 190), 1.0), ((650, 150), 1.0), ((1300, 260), 2.0)])
def test_log_axes_label_powers_of_ten_that_never_overlap(qtbot, size, scale):
    plots = LivePlots()
    qtbot.addWidget(plots)
    plots.set_font_scale(scale)
    plots.resize(*size)
    plots.show()
    qtbot.waitExposed(plots)
    axis = plots.plots[0].getAxis("left")
    for low, high in SPANS:
        errors = 10.0 ** np.linspace(low, high, 400)
        plots.show_run(Rows(errors, errors[::-1]), 399)
        qtbot.wait(1)   # laid out
        decades = [np.floor(low), max(np.ceil(high), np.floor(low) + 1)]   # whole decades, at least one
        assert plots.plots[0].viewRange()[1] == decades
        shown = assert_legible(qtbot, axis)
        assert decades[0] <= exponent(shown[0]) < exponent(shown[-1]) <= decades[1]
        assert_legible(qtbot, plots.plots[1].getAxis("left"))


def test_what_the_labels_say(qtbot):
    plots = LivePlots()
    qtbot.addWidget(plots)
    plots.show()
    qtbot.waitExposed(plots)
    axis = plots.plots[0].getAxis("left")
    every_second = [f"10{k}" for k in "⁻¹⁶ ⁻¹⁴ ⁻¹² ⁻¹⁰ ⁻⁸ ⁻⁶ ⁻⁴ ⁻² ⁰".split()]
    expected = [(300, (-9, -7.3), ["10⁻⁹", "10⁻⁸", "10⁻⁷"]),         # a decade or two: every decade
                (300, (-2, -0.5), ["10⁻²", "10⁻¹", "10⁰"]),
                (300, (-17, 0), every_second),                       # many: as many as fit
                (170, (-17, 0), ["10⁻¹⁵", "10⁻¹⁰", "10⁻⁵", "10⁰"])]
    for height, (low, high), labels in expected:
        plots.resize(900, height)
        errors = 10.0 ** np.linspace(low, high, 400)
        plots.show_run(Rows(errors, errors), 399)
        qtbot.wait(1)
        assert assert_legible(qtbot, axis) == labels
    plots.show_run(None, 0)   # nothing yet: the range errors live in, from FLOOR to 1
    assert plots.plots[0].viewRange()[1] == [np.log10(FLOOR), 0.0]


def test_plots_follow_the_ball_while_playing(qtbot, window):
    """At every frame the plots are either current (their curves end at the ball's time) or were
    brought up to date less than PLOT_INTERVAL of wall time before the frame began."""
    controller, curve = window.controller, window.plots.curves["energy"]
    window.speed.setCurrentIndex(window.speed.findText("Real time"))
    frames = []   # (wall time before drawing, after drawing, the ball's row time, the curve's last time)

    def begin(_force):
        frames.append([time.perf_counter()])

    def end(_force):
        buffer = controller.buffer
        x = curve.getOriginalDataset()[0]
        if controller.state == RUNNING and len(buffer) and x is not None and len(x):
            frames[-1] += [time.perf_counter(), buffer.t[buffer.index_at(controller.play_time)], x[-1]]

    controller.frameReady.disconnect(window.drawing.draw)   # measure around the window's own drawing
    controller.frameReady.connect(begin)
    controller.frameReady.connect(window.drawing.draw)
    controller.frameReady.connect(end)
    window.runs.start()
    qtbot.waitUntil(lambda: sum(len(f) == 4 for f in frames) >= 25, timeout=120_000)
    window.runs.toggle_pause()
    drawn = [f for f in frames if len(f) == 4]
    plotted_at, updates, ball = -np.inf, 0, None
    for started, done, ball_t, plot_t in drawn:
        if plot_t == ball_t:
            plotted_at, updates = done, updates + 1
        elif ball_t != ball:   # the ball moved and the plots did not: they were updated a moment ago
            assert started - plotted_at < PLOT_INTERVAL, (started - plotted_at, ball_t, plot_t)
        ball = ball_t
    assert updates >= 3
    # paused: the cursor at the ball, the curves show all that is computed
    buffer = controller.buffer
    assert controller.state == PAUSED
    assert all(cursor.value() == buffer.t[buffer.index_at(controller.play_time)] for cursor in window.plots.cursors)
    assert curve.getOriginalDataset()[0][-1] == buffer.end_time


def test_f1_over_a_plot_names_that_plot(window):
    plots = window.plots
    for plot, topic in zip(plots.plots, ("plots.html#energy", "plots.html#orthogonality", "plots.html#force")):
        plots.graphics.scene().sigMouseMoved.emit(plot.sceneBoundingRect().center())
        assert helps.topic_at(plots.graphics.viewport()) == topic

"""Events (slip, grip, lift-off, landing) are shown once playback reaches them: on the time
slider, beside it, in the 3-D view and in an exported video; View ▸ Show Future Events shows
them all from the start and is remembered. On a run written out from closed forms
(``scripted``): a slip until T1, a flight from T2, a landing at T3."""

import imageio.v3 as iio
import numpy as np
import pytest
from PySide6 import QtCore

from rollball_app.controller import FINISHED, Run
from rollball_app.preferences import Preferences
from rollball_app.timeline import Marker, merged, telling
from rollball_app.window import MainWindow

from .guitools import FASTEST
from .scripted import T1, T2, T3, ready_to_play

LANDING = np.array([204, 121, 167])   # contact_view.KIND_COLORS["landing"], #cc79a7


def _play(qtbot, window, tmp_path):
    simulation = ready_to_play(window, tmp_path)
    window.controller.start([Run(simulation, window.landscape)])
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=20_000)
    window.drawing.plot()


def shown_times(window) -> tuple[list[float], int]:
    """The events' times on the slider, and how many points the view marks."""
    view = window.view.liftoff
    return [m.time for _, m in window.timeline.slider.markers], len(view.pos) if view.visible() else 0


def test_events_appear_when_playback_reaches_them(qtbot, window, tmp_path):
    _play(qtbot, window, tmp_path)
    expected = {0.0: ([], 0), T1: ([T1], 1), (T1 + T2) / 2: ([T1], 1), T2: ([T1, T2], 2),
                T3 - 1e-3: ([T1, T2], 2), T3: ([T1, T2, T3], 3), 1.0: ([T1, T2, T3], 3)}
    for t, wanted in expected.items():
        window.runs.seek(t)
        assert shown_times(window) == wanted, t
    window.runs.seek(T2 - 1e-3)   # back again: the events ahead are taken away
    assert shown_times(window) == ([T1], 1)
    assert "lift-off" not in window.timeline.events.text()
    # the links and the events' menu only name what is shown
    assert [a.text() for a in window.timeline.more.menu().actions()] in ([], [f"grip at t = {T1:.4g} s"])


def test_show_future_events_shows_them_all_and_is_remembered(qtbot, window, tmp_path, preferences):
    assert not window.future_action.isChecked()
    _play(qtbot, window, tmp_path)
    window.runs.seek(0.0)
    assert shown_times(window) == ([], 0)
    window.menuBar()   # the option is in the View menu
    view_menu = next(a.menu() for a in window.menuBar().actions() if a.text() == "&View")
    assert window.future_action in view_menu.actions()
    window.future_action.trigger()
    assert shown_times(window) == ([T1, T2, T3], 3)
    window.runs.seek(T1 / 2)
    assert shown_times(window) == ([T1, T2, T3], 3)
    assert Preferences(preferences.settings).show_future_events()
    again = MainWindow(preferences)   # the next session starts with it on
    qtbot.addWidget(again)
    assert again.future_action.isChecked() and again.timeline.show_future
    window.future_action.trigger()
    assert shown_times(window) == ([], 0)
    assert not Preferences(preferences.settings).show_future_events()
    again.close()


def test_a_video_shows_each_event_from_the_frame_that_reaches_it(qtbot, window, tmp_path):
    _play(qtbot, window, tmp_path)
    window.runs.seek(1.0)   # every event reached before the export: still the frames show them in turn
    path = tmp_path / "run.gif"
    assert window.exports.export_animation(path, fps=10, size=(320, 240), caption=False)
    frames = iio.imread(path, index=None)[..., :3].astype(int)
    times = np.arange(len(frames)) / 10
    pink = [int((np.abs(frame - LANDING).sum(axis=-1) < 40).sum()) for frame in frames]
    assert all(p == 0 for p, t in zip(pink, times) if t < T3)
    assert all(p > 10 for p, t in zip(pink, times) if t >= T3)


def test_the_most_telling_events_are_linked():
    slips = [Marker(0.384 + 0.003 * k, "#0072b2", f"slip {k}", kind="slip") for k in range(6)]
    liftoff = Marker(0.9, "#ff8c00", "lift-off", kind="lift-off")
    landings = [Marker(1.2 + 0.05 * k, "#cc79a7", f"landing {k}", kind="landing") for k in range(3)]
    events = slips + [liftoff] + landings
    assert telling(events, 2) == [liftoff, landings[0]]
    assert telling(events, 3) == [slips[0], liftoff, landings[0]]
    assert telling([slips[1], slips[0]], 2) == [slips[0], slips[1]]


def test_markers_closer_than_a_few_pixels_merge():
    a, b, c = (Marker(t, "#000000", str(t)) for t in (1.0, 1.1, 2.0))
    assert merged([(100, a), (105, b), (300, c)], 12) == [(100, [a, b]), (300, [c])]
    assert merged([(100, a), (111, b), (122, c)], 12) == [(100, [a, b, c])]   # a chain stays one


def test_the_links_are_telling_and_every_event_is_in_the_menu(qtbot, window, tmp_path):
    _play(qtbot, window, tmp_path)
    text = window.timeline.events.text()
    assert "lift-off" in text and "landing" in text and "grip" not in text
    menu = [a.text() for a in window.timeline.more.menu().actions()]
    assert len(menu) == 3 and menu[0].startswith("grip at t = ")
    menu_grip = window.timeline.more.menu().actions()[0]
    menu_grip.trigger()
    assert window.controller.play_time == T1


@pytest.mark.parametrize("size", [(1024, 768), (1400, 900)])
def test_ridge_jump_keeps_a_usable_slider_and_merges_its_landings(qtbot, window, size):
    """Nine landings close together: the slider keeps most of the width, the links name the
    lift-off and the first landing, the markers drawn are apart (merged where they would touch)."""
    from rollball.examples import EXAMPLES_DIR

    from .guitools import run_to_end
    from rollball_app.timeline import MERGE_PIXELS, SLIDER_SHARE

    window.resize(*size)
    window.files.open_scene(EXAMPLES_DIR / "ridge_jump.json", remember=False)
    run_to_end(qtbot, window)
    qtbot.wait(50)
    timeline, slider = window.timeline, window.timeline.slider
    assert len(timeline.markers) >= 9
    assert slider.width() >= SLIDER_SHARE * timeline.width() >= 300
    text = timeline.events.text()   # the lift-off first; the first landing where there is room
    assert "lift-off" in text and ("landing" in text or size[0] == 1024)
    groups = slider.groups()
    assert sum(len(g) for _, g in groups) == len(timeline.markers)
    assert all(b[0] - a[0] >= MERGE_PIXELS for a, b in zip(groups, groups[1:]))
    assert len(groups) < len(timeline.markers)   # the landings' bounces merged
    menu = timeline.more.menu().actions()
    assert len(menu) == len(timeline.markers)


def test_compare_mode_shows_each_runs_events_when_reached(qtbot, window, tmp_path):
    """Two runs in compare mode: the one that slides and flies has its events shown as playback
    reaches them, named by run; the one that only rolls has none."""
    from .scripted import compare_scripted

    runs = compare_scripted(window, tmp_path)
    window.timeline.set_span(1.0)
    window.speed.setCurrentIndex(FASTEST)
    window.controller.start(runs)
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=20_000)
    window.drawing.plot()
    for t, wanted in ((0.0, ([], 0)), ((T2 + T3) / 2, ([T1, T2], 2)), (1.0, ([T1, T2, T3], 3))):
        window.runs.seek(t)
        assert shown_times(window) == wanted, t
    assert all(m.text.startswith("flies: ") for _, m in window.timeline.slider.markers)
    window.runs.seek(0.0)
    window.future_action.trigger()   # and all of them from the start when asked
    assert shown_times(window) == ([T1, T2, T3], 3)
    window.future_action.trigger()


@pytest.mark.parametrize("size", [(1024, 768), (1400, 900)])
def test_presentation_mode_shows_events_when_reached_and_a_clicked_marker_jumps(qtbot, window, size):
    """ridge_jump in presentation mode: at 0.8 s only the lift-off is shown; at the end every
    landing, merged where they crowd; a mouse click on a merged marker shows its first event."""
    from rollball.examples import EXAMPLES_DIR

    from .guitools import run_to_end
    from rollball_app.timeline import SLIDER_SHARE

    window.resize(*size)
    window.files.open_scene(EXAMPLES_DIR / "ridge_jump.json", remember=False)
    window.presentation_action.setChecked(True)
    qtbot.wait(50)
    run_to_end(qtbot, window)
    liftoff = window.controller.simulation.liftoff_time
    window.runs.seek(liftoff + 0.05)
    timeline, slider = window.timeline, window.timeline.slider
    assert [m.kind for _, m in slider.markers] == ["lift-off"]
    assert "lift-off" in timeline.events.text() and "landing" not in timeline.events.text()
    assert shown_times(window)[1] == 1
    window.runs.seek(window.controller.end_time)
    qtbot.wait(20)
    assert slider.width() >= SLIDER_SHARE * timeline.width()
    assert "lift-off" in timeline.events.text()   # in large text too, the lift-off is a link
    x, group = next((x, g) for x, g in slider.groups() if len(g) > 1)
    qtbot.mouseClick(slider, QtCore.Qt.MouseButton.LeftButton, pos=QtCore.QPoint(x, slider.height() // 2))
    assert window.controller.play_time == group[0].time
    assert [m.time for _, m in slider.markers] == [m.time for m in timeline.markers if m.time <= group[0].time]
    window.presentation_action.setChecked(False)


def test_larger_text_lays_the_links_out_again(qtbot, window, tmp_path):
    """At the same width, a larger text (View → Text Size) leaves fewer links, never a squeezed slider:
    it keeps half the width where links are shown, and its least width (``SLIDER_WIDTH``) where
    the time's label and the events' menu alone take more than the other half."""
    from rollball_app.timeline import SLIDER_SHARE
    from rollball_app.window import SLIDER_WIDTH

    window.resize(1024, 768)
    _play(qtbot, window, tmp_path)
    timeline = window.timeline
    for action in window.text_size_group.actions():   # every text size, the largest last
        action.trigger()
        qtbot.wait(300)
        needed = (timeline.events.sizeHint().width() if timeline.events.isVisibleTo(timeline) else 0) \
            + (timeline.more.sizeHint().width() if timeline.more.isVisibleTo(timeline) else 0)
        links = timeline.events.isVisibleTo(timeline)
        assert timeline.slider.width() >= (SLIDER_SHARE * timeline.width() - 1 if links else SLIDER_WIDTH), \
            action.text()
        # (no link at all: the events' menu button alone, however little room is left)
        assert needed <= (1 - SLIDER_SHARE) * timeline.width() - timeline.label.width() or not links, action.text()
    window.text_size_group.actions()[0].trigger()

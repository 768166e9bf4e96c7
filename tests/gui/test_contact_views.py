"""The contact's modes and transitions as the window shows them, on a run written out from closed
forms (``scripted``): the trail coloured by mode, a marker at every transition that moves the
time there, the slip and dissipation readouts, the normal force 0 in flight with the modes
shaded behind it."""

import numpy as np

from rollball_app import contact_view
from rollball_app.controller import FINISHED, Run
from rollball.examples import EXAMPLES_DIR
from rollball.trajectory import CENTER, FLYING, ROLLING, SLIDING

from .guitools import FASTEST
from .scripted import MU, SCENE, T1, T2, T3, TRANSITIONS, V0, compare_scripted, ready_to_play


def _play(qtbot, window, tmp_path):
    simulation = ready_to_play(window, tmp_path)
    window.plots.set_duration(simulation.t_end)
    events = []
    window.controller.event.connect(lambda i, kind, t: events.append((kind, t)))
    window.controller.start([Run(simulation, window.landscape)])
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=20_000)
    window.drawing.plot()
    return events


def test_trail_coloured_by_mode_and_a_marker_at_every_transition(qtbot, window, tmp_path):
    events = _play(qtbot, window, tmp_path)
    # each transition said once as playback passes it; a flying ball's lift-off is not the glued one's
    assert events == [(c.kind, c.time) for c in TRANSITIONS]
    assert contact_view.sentence("liftoff", T2).endswith("the ball leaves the surface and flies")
    buffer = window.controller.buffer
    t, mode = buffer.t, buffer.mode
    assert set(mode[t < T1]) == {SLIDING} and set(mode[(t > T2) & (t < T3)]) == {FLYING}
    assert set(mode[(t > T1) & (t < T2)]) == {ROLLING}
    colors = window.view.trail.color   # the colour of each point, by its row's mode
    picked = buffer.trail_rows(len(buffer) - 1)
    assert len(colors) == len(picked)
    for code in (ROLLING, SLIDING, FLYING):
        assert np.allclose(colors[buffer.mode[picked] == code], contact_view.rgba(contact_view.MODE_COLORS[code]))
    # in flight the trail follows the ball's lowest point: above the plane, as high as the centre less r
    trail = buffer.trail(len(buffer) - 1, lift=0.3, picked=picked)
    flying = mode[picked] == FLYING
    assert np.allclose(trail[flying, 2], buffer.rows[picked[flying], CENTER][:, 2] - 0.7 * SCENE.ball.radius)
    assert np.allclose(trail[~flying, 2], 0.3 * SCENE.ball.radius)

    markers = [m for _, m in window.timeline.slider.markers]
    assert [m.time for m in markers] == [c.time for c in TRANSITIONS]
    assert [m.color for m in markers] == [contact_view.KIND_COLORS[k] for k in ("grip", "liftoff", "landing")]
    assert "0.5 J lost" in markers[2].text
    window.timeline.slider.markerClicked.emit(markers[2].time)   # a marker moves the time there
    assert window.controller.play_time == T3
    assert len(window.view.liftoff.pos) == 3                     # every transition reached marked in the view
    window.timeline.events.linkActivated.emit(repr(T1))          # and so does its link
    assert window.controller.play_time == T1
    assert len(window.view.liftoff.pos) == 1                     # the events ahead are not shown yet
    assert [m.time for _, m in window.timeline.slider.markers] == [T1]
    assert f"landing at t = {T3:.4g} s (0.5 J lost)" in window.message.toolTip()
    window.closeup_action.setChecked(True)   # the close-up's trail by mode too
    window.runs.seek(T3 - 0.05)
    near = window.closeup.trail.color
    allowed = [contact_view.rgba(contact_view.MODE_COLORS[k]) for k in (ROLLING, FLYING)]
    assert len(near) and all(any(np.allclose(c, a, atol=1e-6) for a in allowed) for c in near)
    assert any(np.allclose(c, allowed[1], atol=1e-6) for c in near)   # the flight before the landing


def test_readouts_and_the_normal_force_in_flight(qtbot, window, tmp_path):
    _play(qtbot, window, tmp_path)
    readouts = window.readouts
    assert readouts["slip"].isVisible() and readouts["dissipated"].isVisible()
    window.runs.seek(0.1)   # sliding: v − rω = v₀ − (7/2) μ g t
    assert readouts["slip"].text() == f"{V0 - 3.5 * MU * 9.81 * 0.1:.3g} m/s"
    window.runs.seek(0.5)   # rolling: friction took 2/7 of the kinetic energy, and the error counts it
    assert readouts["slip"].text() == "0 m/s" and readouts["dissipated"].text() == f"{2 / 7 * 2.0:.5g} J"
    assert abs(float(readouts["drift"].text())) < 1e-12
    window.runs.seek((T2 + T3) / 2)
    assert readouts["force"].text() == "0 N"
    force = window.plots.curves["force"].getData()[1]
    assert force.min() == 0.0   # not negative, no gap: 0 in flight
    assert not np.isnan(force).any()
    shown = window.plots.mode_spans.shown
    assert [mode for *_, mode in shown] == [SLIDING, FLYING]
    assert abs(shown[1][0] - T2) < 0.011 and abs(shown[1][1] - T3) < 0.011
    assert [line.value() for line in window.plots.mode_spans.lines] == [T3]   # the landing
    assert window.plots.plots[0].property("plotTitle").startswith("|E + D − E₀|")
    # a scene of the 2011 model shows neither slip nor dissipation
    window.files.open_scene(EXAMPLES_DIR / "hills.json", remember=False)
    assert not readouts["slip"].isVisible() and readouts.titles["drift"].text() == "(E − E₀)/E₀"
    assert window.plots.plots[0].property("plotTitle").startswith("|E − E₀|") and not window.plots.mode_spans.lines


def test_spans_from_modes():
    t = np.arange(8.0)
    assert contact_view.spans(t, [0, 1, 1, 0, 2, 2, 2, 0]) == [(1.0, 3.0, SLIDING), (4.0, 7.0, FLYING)]
    assert contact_view.spans(t[:2], [2, 2]) == [(0.0, 1.0, FLYING)]
    assert contact_view.summary(TRANSITIONS) == (f"; grip at t = {T1:.4g} s, lift-off at t = {T2:.4g} s, "
                                                 f"landing at t = {T3:.4g} s (0.5 J lost)")
    assert contact_view.summary(TRANSITIONS, listed=2) == "; 1 grip, 1 lift-off, 1 landing (0.5 J lost)"
    assert contact_view.summary(()) == ""


def test_compare_mode_each_run_shows_its_own_transitions(qtbot, window, tmp_path):
    """One run slides and flies, the other only rolls: each trail in its own colour's shades, the
    markers of the one that has transitions named by run, nothing of the other."""
    runs = compare_scripted(window, tmp_path)
    window.readouts.show_contact(True, columns=False)
    window.timeline.set_span(1.0)
    window.speed.setCurrentIndex(FASTEST)
    window.controller.start(runs)
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=20_000)
    window.drawing.plot()
    markers = [m for _, m in window.timeline.slider.markers]
    assert [m.text.split(":")[0] for m in markers] == ["flies"] * 3
    flying, rolling = (window.view.trails[k].color for k in (0, 1))
    assert np.allclose(rolling, contact_view.trail_colors([ROLLING], "#2ca02c")[0])
    picked = runs[0].buffer.trail_rows(len(runs[0].buffer) - 1)
    assert np.allclose(flying, contact_view.trail_colors(runs[0].buffer.mode[picked], "#1f77b4"))
    assert len({tuple(c) for c in flying}) == 3   # rolling, sliding and flying told apart
    assert len(window.view.liftoff.pos) == 3
    assert window.readouts.titles["drift"].text() == "(E+D−E₀)/E₀" and window.readouts["slip"].isHidden()
    summary = window.compare.summary   # each run's landings and dissipation in the summary
    summary.set_runs(runs)
    assert [summary.value("Landings", k) for k in (0, 1)] == ["1", "0"]
    assert summary.value("Mode at end", 0) == "rolling"
    assert summary.value("Dissipated (J)", 0) == f"{2 / 7 * 2.0 + 0.5:.3g}"
    window.compare_action.setChecked(False)

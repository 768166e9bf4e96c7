"""The live path and the start's handles in the real window: the preview follows every change
of the scene and gives way to a run; the ball and its velocity arrow dragged on the surface set
the start (checked against where Qt's own matrices draw the points dragged to)."""

import numpy as np
import pytest
from PySide6 import QtCore, QtGui, QtWidgets

from rollball.examples import EXAMPLES_DIR
from rollball_app.compare_runs import CompareRun
from rollball_app.controller import FINISHED, READY
from rollball_app.view3d import ARROW_SECONDS
from rollball import parse_runs

from .guitools import FASTEST, run_to_end, set_field


def previewed(window):
    return window.view.preview.visible() and window.start_editing.scene == window.scene \
        and not window.start_editing.preview.busy


def wait_preview(qtbot, window):
    qtbot.waitUntil(lambda: previewed(window), timeout=30_000)
    return np.array(window.view.preview.pos)


def pixel(view, point) -> QtCore.QPointF:
    """Where the view draws a world point, by Qt's own matrices."""
    w, h = view.width(), view.height()
    m = view.projectionMatrix((0, 0, w, h), (0, 0, w, h)) * view.viewMatrix()
    p = m.map(QtGui.QVector3D(*map(float, point)))   # normalised device coordinates
    return QtCore.QPointF((p.x() + 1) * w / 2, (1 - p.y()) * h / 2)


def mouse(view, kind, pos, buttons=QtCore.Qt.MouseButton.LeftButton, modifiers=QtCore.Qt.KeyboardModifier.NoModifier):
    types = {"press": QtCore.QEvent.Type.MouseButtonPress, "move": QtCore.QEvent.Type.MouseMove,
             "release": QtCore.QEvent.Type.MouseButtonRelease}
    button = QtCore.Qt.MouseButton.NoButton if kind == "move" else QtCore.Qt.MouseButton.LeftButton
    held = QtCore.Qt.MouseButton.NoButton if kind == "release" else buttons
    event = QtGui.QMouseEvent(types[kind], pos, view.mapToGlobal(pos), button, held, modifiers)
    QtWidgets.QApplication.sendEvent(view, event)


def drag(view, points, modifiers=QtCore.Qt.KeyboardModifier.NoModifier):
    """Press at the first pixel, move through the others, release at the last."""
    mouse(view, "press", points[0], modifiers=modifiers)
    for a, b in zip(points, points[1:]):
        for w in (0.5, 1.0):
            mouse(view, "move", a + (b - a) * w, modifiers=modifiers)
    mouse(view, "release", points[-1], modifiers=modifiers)


def surface(window, x, y):
    return np.array([x, y, float(window.landscape.height(x, y))])


def test_the_preview_follows_the_scene_and_gives_way_to_a_run(qtbot, window):
    points = wait_preview(qtbot, window)
    r = window.scene.ball.radius
    assert np.linalg.norm(points[0] - window.view.ball_center) < 1e-6      # from the ball's centre (float32 on the GPU)
    assert np.linalg.norm(points[-1] - points[0]) > 10 * r                  # it goes somewhere
    set_field(qtbot, window, "start.x", "-0.5")
    points = wait_preview(qtbot, window)
    assert points[0][0] == pytest.approx(-0.5, abs=2 * r)
    run_to_end(qtbot, window)
    assert not window.view.preview.visible() and not window.view.arrow_head.visible()
    assert window.start_editing.scene is None
    trail = np.array(window.view.trail.pos)
    window.runs.reset()
    again = wait_preview(qtbot, window)
    # the preview is the start of the path the run took (another method: to a few mm)
    n = int(np.argmin(np.linalg.norm(trail - trail[0] - (again[100] - again[0]), axis=1)))
    assert np.linalg.norm(trail[n] - trail[0] - (again[100] - again[0])) < 0.01


def test_dragging_the_ball_moves_the_start_over_the_surface(qtbot, window):
    view, panel = window.view, window.panel
    wait_preview(qtbot, window)
    s = window.scene.start
    steps = window.undo_stack.count()
    target = (1.0, 0.6)
    path = [pixel(view, surface(window, s.x, s.y))] + [
        pixel(view, surface(window, s.x + w * (target[0] - s.x), s.y + w * (target[1] - s.y))) for w in (0.3, 0.7, 1.0)]
    drag(view, path)
    start = window.scene.start
    assert (start.x, start.y) == pytest.approx(target, abs=0.02)
    assert panel.numbers["start.x"].text() == repr(start.x) and len(repr(start.x)) <= 6   # rounded for reading
    assert window.undo_stack.count() == steps + 1 and window.undo_stack.undoText() == "Move start point"
    points = wait_preview(qtbot, window)
    assert np.linalg.norm(points[0][:2] - target) < 0.1                 # the preview follows
    window.undo_stack.undo()
    assert (window.scene.start.x, window.scene.start.y) == (s.x, s.y)


def test_dragging_the_arrow_sets_the_start_velocity(qtbot, window):
    view = window.view
    wait_preview(qtbot, window)
    center, normal, _ = view.start
    d = window.landscape.evaluate(window.scene.start.x, window.scene.start.y)
    wanted = np.array([0.8, -0.5])
    tip = center + ARROW_SECONDS * np.array([*wanted, d[1] * wanted[0] + d[2] * wanted[1]])
    shift = QtCore.Qt.KeyboardModifier.ShiftModifier
    drag(view, [pixel(view, center), pixel(view, 0.5 * (center + tip)), pixel(view, tip)], modifiers=shift)
    start = window.scene.start
    assert (start.vx, start.vy) == pytest.approx(wanted, abs=0.02)
    assert window.undo_stack.undoText() == "Change start velocity"
    assert view.arrow_head.visible()
    # the arrow's head now grabs without Shift: dragged back to the ball, the velocity is zero
    tip = center + ARROW_SECONDS * np.array([start.vx, start.vy, d[1] * start.vx + d[2] * start.vy])
    drag(view, [pixel(view, tip), pixel(view, 0.5 * (center + tip)), pixel(view, center)])
    assert (window.scene.start.vx, window.scene.start.vy) == pytest.approx((0.0, 0.0), abs=0.02)


def test_a_drag_elsewhere_turns_the_camera_and_a_run_has_no_handles(qtbot, window):
    view = window.view
    wait_preview(qtbot, window)
    before, azimuth = window.scene, view.opts["azimuth"]
    corner = QtCore.QPointF(20, view.height() - 20)
    drag(view, [corner, corner + QtCore.QPointF(60, 0)])
    assert window.scene == before and view.opts["azimuth"] != azimuth
    window.speed.setCurrentIndex(FASTEST)
    window.runs.start()
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=30_000)
    s = window.scene.start
    ball = pixel(view, surface(window, s.x, s.y))
    drag(view, [ball, ball + QtCore.QPointF(80, 40)])
    assert window.scene == before                                       # the camera turned instead


def test_compare_mode_previews_before_its_runs_and_not_during_them(qtbot, window):
    set_field(qtbot, window, "duration", "1")
    window.compare.enter([CompareRun.of(spec, window.scene) for spec in parse_runs("euler/classic,rk4")])
    wait_preview(qtbot, window)
    window.speed.setCurrentIndex(FASTEST)
    window.runs.start()
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=60_000)
    assert not window.view.preview.visible()
    window.runs.seek(0.5)                                               # playback: still none
    assert not window.view.preview.visible() and window.controller.state != READY
    window.runs.reset()
    wait_preview(qtbot, window)
    window.compare_action.setChecked(False)


def test_a_scene_with_its_own_start_omega_keeps_its_velocity(qtbot, window, tmp_path):
    import json
    data = json.loads((EXAMPLES_DIR / "flat.json").read_text())
    data.update(version=3)
    data["start"].update(vx=0.5, vy=0.0, spin=0.0, omega=[0.0, 5.0, 0.0])   # rolls: ω = N × ċ / r
    data["ball"]["radius"] = 0.1
    path = tmp_path / "omega.json"
    path.write_text(json.dumps(data))
    assert window.files.open_scene(path)
    view = window.view
    wait_preview(qtbot, window)
    center = view.start[0]
    assert view.arrow_head.visible()
    tip = center + ARROW_SECONDS * np.array([0.5, 0.0, 0.0])
    before = window.scene
    drag(view, [pixel(view, tip), pixel(view, tip + [0.3, 0.3, 0.0])])      # the head does not move
    assert window.scene.start.vx == before.start.vx and window.scene.start.omega == (0.0, 5.0, 0.0)


def test_with_follow_ball_the_camera_waits_for_the_drag_to_end(qtbot, window):
    view = window.view
    window.follow_action.setChecked(True)
    wait_preview(qtbot, window)
    s = window.scene.start
    centre = view.opts["center"]
    target = (s.x + 0.6, s.y + 0.3)
    pixels = [pixel(view, surface(window, s.x + w * 0.6, s.y + w * 0.3)) for w in (0.0, 0.5, 1.0)]
    mouse(view, "press", pixels[0])
    for p in pixels[1:]:
        mouse(view, "move", p)
    assert view.opts["center"] == centre                     # still while the mouse drags
    mouse(view, "release", pixels[-1])
    start = window.scene.start
    assert (start.x, start.y) == pytest.approx(target, abs=0.02)   # where the mouse went, no run-away
    assert np.allclose([view.opts["center"].x(), view.opts["center"].y()], view.ball_center[:2])
    window.follow_action.setChecked(False)

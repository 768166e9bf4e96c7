"""The path preview and the geometry of dragging the start: against closed forms (the incline,
a ray and a paraboloid, the view's own projection), and the preview's cancelling."""

import math
import threading

import numpy as np
import pytest

from rollball import Scene
from rollball.comparison import Cancelled
from rollball.examples import EXAMPLES_DIR
from rollball_app.picking import mouse_ray, on_screen, ray_plane, ray_surface, rounded
from rollball_app.preview import PREVIEW_ROWS, PREVIEW_SECONDS, PathPreview, compute

G = 9.81


def test_the_preview_on_an_incline_is_the_closed_form():
    scene = Scene.load(EXAMPLES_DIR / "incline.json")      # z = -0.5 x, duration 1.5 s
    s, r = 0.5, scene.ball.radius
    preview = compute(scene)
    assert preview.t_end == pytest.approx(1.5) and preview.status == "ok"
    assert len(preview.points) == PREVIEW_ROWS + 1
    t = np.linspace(0.0, 1.5, PREVIEW_ROWS + 1)
    sin, cos = s / math.hypot(1, s), 1 / math.hypot(1, s)
    a = 5 / 7 * G * sin
    x = scene.start.x + 0.5 * a * cos * t ** 2
    y = scene.start.y + scene.start.vy * t
    normal = np.array([s, 0.0, 1.0]) / math.hypot(1, s)
    expected = np.stack([x, y, -s * x], axis=1) + r * normal      # the centre
    np.testing.assert_allclose(preview.points, expected, atol=1e-9)


def test_a_preview_is_a_few_seconds_and_stops_when_cancelled():
    scene = Scene.load(EXAMPLES_DIR / "hills.json")        # 10 s long
    assert compute(scene).t_end == pytest.approx(PREVIEW_SECONDS)
    cancel = threading.Event()
    cancel.set()
    with pytest.raises(Cancelled):
        compute(scene, cancel)


def test_only_the_latest_scenes_preview_is_brought(qtbot):
    import dataclasses
    base = Scene.load(EXAMPLES_DIR / "hills.json")
    scenes = [dataclasses.replace(base, start=dataclasses.replace(base.start, x=0.1 * k)) for k in range(8)]
    preview = PathPreview()
    brought = []
    preview.ready.connect(brought.append)
    for scene in scenes:
        preview.request(scene)
    qtbot.waitUntil(lambda: not preview.busy and len(brought) > 0, timeout=30_000)
    assert [p.scene for p in brought] == [scenes[-1]]
    assert brought[0].points[0, 0] == pytest.approx(0.7, abs=0.05)
    preview.request(scenes[-1])                 # asked again: computed again, brought again
    qtbot.waitUntil(lambda: not preview.busy and len(brought) == 2, timeout=30_000)
    preview.clear()
    preview.shutdown()


def _camera():
    """A perspective camera's projection times view matrix, looking at the origin from (4, -6, 5)."""
    eye, target, up = np.array([4.0, -6.0, 5.0]), np.zeros(3), np.array([0.0, 0.0, 1.0])
    f = (target - eye) / np.linalg.norm(target - eye)
    s = np.cross(f, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    view = np.eye(4)
    view[:3, :3] = np.stack([s, u, -f])
    view[:3, 3] = -view[:3, :3] @ eye
    near, far, fov, aspect = 0.01, 100.0, math.radians(60), 800 / 600
    k = 1 / math.tan(fov / 2)
    proj = np.array([[k / aspect, 0, 0, 0], [0, k, 0, 0],
                     [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0]])
    return proj @ view, eye


def test_the_ray_under_a_pixel_meets_the_surface_where_that_point_is_drawn():
    matrix, eye = _camera()

    def height(x, y):
        return 0.1 * (np.asarray(x) ** 2 + np.asarray(y) ** 2) - 1.0
    for x, y in [(0.5, -0.25), (-1.2, 0.7), (1.9, 1.9), (0.0, 0.0)]:
        point = np.array([x, y, height(x, y)])
        pixel = on_screen(matrix, point, 800, 600)
        origin, direction = mouse_ray(matrix, *pixel, 800, 600)
        assert np.linalg.norm(np.cross(point - origin, direction)) < 1e-9      # the ray passes through it
        hit = ray_surface(origin, direction, height, -3.0, 3.0)
        np.testing.assert_allclose(hit, point, atol=1e-9)                       # the first crossing is it
    origin, direction = mouse_ray(matrix, 400, 5, 800, 600)                     # the sky: no surface
    assert ray_surface(origin, direction, lambda x, y: np.full(np.shape(x), -np.inf), -3, 3) is None


def test_a_ray_meets_a_plane_and_dragged_values_read_plainly():
    hit = ray_plane(np.array([0.0, 0.0, 5.0]), np.array([0.0, 0.6, -0.8]), np.zeros(3), np.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(hit, [0.0, 3.75, 0.0])
    assert ray_plane(np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([0, 0, 1.0])) is None
    assert rounded(0.43712873, 0.006) == 0.437 and rounded(-0.0001, 0.01) == 0.0
    assert str(rounded(-0.0001, 0.01)) == "0.0"


@pytest.mark.parametrize("between", [("other",), ("other", "first"), ("clear", "first"), ("first",)])
def test_a_request_between_a_workers_done_and_ended_is_not_lost(qtbot, monkeypatch, between):
    """The worker says done, then ended (both queued to the GUI thread), then lets go: whatever
    is asked for in between (another scene, back to the first, cleared and asked again) is the
    preview brought last."""
    import dataclasses

    import rollball_app.preview as preview_module
    first = Scene.load(EXAMPLES_DIR / "incline.json")
    other = dataclasses.replace(first, start=dataclasses.replace(first.start, x=first.start.x + 0.5))
    hooked_up = threading.Event()

    def held(scene, cancel=None):   # the first computation waits until the hook below is connected
        hooked_up.wait(10)
        return compute(scene, cancel)
    monkeypatch.setattr(preview_module, "compute", held)
    preview = PathPreview()
    brought, hooked = [], []
    preview.ready.connect(brought.append)
    preview.request(first)

    def in_between(_result):   # connected after the preview's own slot: runs between its done and ended
        hooked.append(preview.busy)
        for step in between:
            preview.clear() if step == "clear" else preview.request(first if step == "first" else other)
    preview.worker.done.connect(in_between)
    hooked_up.set()
    latest = first if between[-1] == "first" else other
    qtbot.waitUntil(lambda: bool(hooked and not preview.busy and brought and brought[-1].scene == latest),
                    timeout=30_000)
    assert hooked == [True]                   # the hook ran while the first worker was still held
    assert brought[0].scene == first          # the first one was brought at its done
    qtbot.wait(100)
    assert not preview.busy and brought[-1].scene == latest
    preview.shutdown()

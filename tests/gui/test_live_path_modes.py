"""The live path before a run is coloured by the mode it predicts, in the trail's colours:
billiard's shot slides until t₁ = 2v₀/(7μg) and rolls after it; the lift-off example flies."""

import numpy as np

from rollball.examples import EXAMPLES_DIR
from rollball.trajectory import FLYING, ROLLING, SLIDING
from rollball_app import contact_view


def preview_of(qtbot, window, name):
    window.files.open_scene(EXAMPLES_DIR / f"{name}.json", remember=False)
    editing = window.start_editing
    qtbot.waitUntil(lambda: window.view.preview.visible() and editing.scene == window.scene
                    and not editing.preview.busy, timeout=30_000)
    computed = editing.preview
    return np.asarray(window.view.preview.color), computed


def color(mode):
    return contact_view.rgba(contact_view.MODE_COLORS[mode])


def test_billiard_preview_slides_then_rolls(qtbot, window):
    previews = []
    window.start_editing.preview.ready.connect(previews.append)
    colors, _ = preview_of(qtbot, window, "billiard")
    preview = previews[-1]
    scene = window.scene
    t1 = 2 * scene.start.vx / (7 * scene.contact.friction * scene.gravity)
    step = preview.times[1] - preview.times[0]
    assert len(colors) == len(preview.points) == len(preview.times)
    assert np.allclose(colors[preview.times < t1 - step], color(SLIDING))
    assert np.allclose(colors[preview.times > t1 + step], color(ROLLING))
    assert (preview.times < t1 - step).sum() > 10 and (preview.times > t1 + step).sum() > 10


def test_liftoff_preview_shows_the_flight(qtbot, window):
    previews = []
    window.start_editing.preview.ready.connect(previews.append)
    colors, _ = preview_of(qtbot, window, "liftoff")
    preview = previews[-1]
    flying = preview.modes == FLYING
    assert flying.any() and (~flying).any()
    assert np.allclose(colors[flying], color(FLYING))
    assert np.allclose(colors[~flying], color(ROLLING))

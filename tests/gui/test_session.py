"""The scene session, without the window: what a change touches, and its undo history."""

import dataclasses

from rollball import Scene
from rollball.examples import EXAMPLES_DIR
from rollball_app.session import SceneSession, changes, run_spec


def hills() -> Scene:
    return Scene.load(EXAMPLES_DIR / "hills.json")


def test_what_a_change_touches():
    scene = hills()
    assert changes(None, scene) == (changes(None, scene).__class__(True, True, True))
    described = dataclasses.replace(scene, description="another text")
    assert changes(scene, described) == changes(scene, scene) == type(changes(scene, scene))(False, False, False)
    longer = dataclasses.replace(scene, duration=scene.duration + 1)
    assert changes(scene, longer).run and not changes(scene, longer).surface
    moved = dataclasses.replace(scene, start=dataclasses.replace(scene.start, x=scene.start.x + 0.5))
    assert changes(scene, moved).surface and changes(scene, moved).run and not changes(scene, moved).grid
    assert str(run_spec(scene)) == "rk4"


def test_edits_loads_and_revert_are_undone_in_order(qapp):
    shown = []
    session = SceneSession(shown.append)
    scene = hills()
    session.opened(EXAMPLES_DIR / "hills.json", scene, example=True)
    session.shown = scene
    edited = dataclasses.replace(scene, duration=3.0)
    session.edited(scene, edited)        # a field edit: already shown, one undo step
    assert shown == [] and session.undo.count() == 1
    loaded = dataclasses.replace(edited, duration=4.0)
    assert session.load(edited, loaded, "Load Run from Sweep") and shown == [loaded]
    assert not session.load(loaded, loaded, "again")   # the same scene: nothing
    assert session.revert(loaded) and shown[-1] == scene
    assert session.undo.undoText() == "Revert to saved"
    session.undo.undo()
    session.undo.undo()
    session.undo.undo()
    assert shown[-3:] == [loaded, edited, scene]
    session.opened(EXAMPLES_DIR / "hills.json", scene, example=True)
    assert session.undo.count() == 0

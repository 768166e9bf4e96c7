"""The example scenes shipped with RollBall: the JSON files in ``resources/examples/`` (installed
as package data of ``rollball.resources``, so found from any folder, in a checkout as in an
installed wheel). A scene can be named by its file or, for an example, by its name alone."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from . import resources

if TYPE_CHECKING:   # the scene (sympy, numba) is loaded only to read one: naming a scene is instant
    from .scene import Scene

EXAMPLES_DIR: Path = resources.path("examples")
DEFAULT_EXAMPLE = EXAMPLES_DIR / "hills.json"


def example_names() -> list[str]:
    """The examples' names (their file names without ``.json``), sorted."""
    return sorted(entry.name[:-5] for entry in EXAMPLES_DIR.iterdir() if entry.name.endswith(".json"))


def example_scenes() -> list[tuple[Path, Scene]]:
    """Every example scene, sorted by file name."""
    from .scene import Scene

    return [(EXAMPLES_DIR / f"{name}.json", Scene.load(EXAMPLES_DIR / f"{name}.json"))
            for name in example_names()]


def example_descriptions() -> list[tuple[str, str]]:
    """Every example's name and description, sorted by name: read from the files as they are,
    without loading the scenes (which checks their formulas with sympy; the tests load every
    example)."""
    return [(name, json.loads((EXAMPLES_DIR / f"{name}.json").read_text(encoding="utf-8-sig")).get("description", ""))
            for name in example_names()]


def example_tracks() -> list[str]:
    """The file names of the example tracks (measured-track CSV files, ``Track.load``), sorted."""
    return sorted(entry.name for entry in EXAMPLES_DIR.iterdir() if entry.name.endswith(".csv"))


def track_path(text: str) -> Path:
    """The track file ``text`` names: what exists at that path, else the example track of that
    name (``billiard_track.csv``), else the path as given (reading it says what is wrong)."""
    path = Path(text)
    if path.exists() or path.parent != Path(".") or path.name not in example_tracks():
        return path
    return EXAMPLES_DIR / path.name


def scene_path(text: str) -> Path:
    """The scene file ``text`` names: what exists at that path (reading it says what is wrong
    with it), else the example of that name (with or without ``.json``). Raises
    ``FileNotFoundError`` with a one-line message listing the examples when it is neither."""
    path = Path(text)
    if path.exists():
        return path
    name = path.name[:-5] if path.name.endswith(".json") else path.name
    if path.parent == Path(".") and name in example_names():
        return EXAMPLES_DIR / f"{name}.json"
    raise FileNotFoundError(f"{text}: no such scene file or example "
                            f"(examples: {', '.join(example_names())})")

"""The example scenes shipped in ``resources/examples/``."""

from __future__ import annotations

from pathlib import Path

from .scene import Scene

EXAMPLES_DIR = Path(__file__).resolve().parent.parent / "resources" / "examples"
DEFAULT_EXAMPLE = EXAMPLES_DIR / "hills.json"


def example_scenes() -> list[tuple[Path, Scene]]:
    """Every example scene, sorted by file name."""
    return [(path, Scene.load(path)) for path in sorted(EXAMPLES_DIR.glob("*.json"))]

"""The README's table of example scenes, made from the example files themselves
(``resources/examples/*.json``: name, landscape, what the contact allows, description). After adding
or changing an example run

    .venv/bin/python scripts/examples_table.py

which rewrites the lines between the README's two markers; ``tests/test_readme.py`` fails while the
README and the files differ.
"""

from __future__ import annotations

import sys
from pathlib import Path

from rollball.examples import example_scenes

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
BEGIN = "<!-- examples: made by scripts/examples_table.py from resources/examples/*.json -->"
END = "<!-- examples end -->"


def contact(scene) -> str:
    """What the ball can do in this scene: always roll (the 2011 model), slide, fly, come to rest."""
    modes = ["rolls"] if scene.contact.friction is None else ["slides", "rolls"]
    if scene.contact.after_liftoff == "fly":
        modes.append("flies")
    if scene.dissipates:
        modes.append("comes to rest")
    return ", ".join(modes)


def cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def table() -> str:
    rows = ["| example | landscape z = | the ball | what it shows |", "|---|---|---|---|"]
    for path, scene in example_scenes():
        rows.append(f"| `{path.stem}` | `{cell(scene.landscape)}` | {contact(scene)} | {cell(scene.description)} |")
    return "\n".join(rows)


def with_table(readme: str) -> str:
    """The README's text with the table between its markers made afresh."""
    head, begin, rest = readme.partition(BEGIN)
    _, end, tail = rest.partition(END)
    if not begin or not end:
        raise ValueError(f"README.md: the markers {BEGIN!r} and {END!r} are missing")
    return f"{head}{BEGIN}\n{table()}\n{END}{tail}"


def main() -> int:
    README.write_text(with_table(README.read_text(encoding="utf-8")), encoding="utf-8")
    print("examples_table: wrote the table of examples into README.md", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The README is a newcomer's page: short, right about what RollBall is, and its table of examples is
the example files' (scripts/examples_table.py writes it)."""

import dataclasses
import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"


def _script(name):
    spec = importlib.util.spec_from_file_location(f"scripts_{name}", ROOT / "scripts" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_readme_is_at_most_250_lines_and_2000_words():
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 250
    assert len(text.split()) <= 2000


def test_what_rollball_is_says_rolling_sliding_and_flying():
    first = README.read_text(encoding="utf-8").split("\n\n")[1]   # the paragraph under the title
    assert "rolling, sliding and flying" in first and "without slipping" not in first
    description = re.search(r'^description = "(.*)"$', (ROOT / "pyproject.toml").read_text(encoding="utf-8"), re.M)
    assert "rolling, sliding and flying" in description.group(1)
    shown = subprocess.run([sys.executable, "-m", "rollball", "--help"], capture_output=True, text=True,
                           cwd=ROOT, check=True).stdout
    assert "rolling, sliding and flying" in " ".join(shown.split())


def test_the_readme_says_how_long_the_suite_takes_and_where_to_report_a_problem():
    text = " ".join(README.read_text(encoding="utf-8").split())
    assert "about 8 minutes on 2 cores" in text
    assert "issue tracker" in text and "[LICENSE](LICENSE)" in text and "[CITATION.cff](CITATION.cff)" in text


def test_the_table_of_examples_is_the_example_files():
    table = _script("examples_table")
    text = README.read_text(encoding="utf-8")
    assert table.with_table(text) == text, "run: .venv/bin/python scripts/examples_table.py"
    rows = re.findall(r"^\| `(\w+)` \|", text, flags=re.M)
    assert rows == sorted(p.stem for p in (ROOT / "resources" / "examples").glob("*.json"))


def test_the_table_follows_an_example_that_changed(tmp_path, monkeypatch):
    from rollball.examples import example_scenes

    table = _script("examples_table")
    (path, scene), *others = example_scenes()
    scene = dataclasses.replace(scene, description="A new description | with a bar.")
    monkeypatch.setattr(table, "example_scenes", lambda: [(path, scene), *others])
    text = README.read_text(encoding="utf-8")
    changed = table.with_table(text)
    assert changed != text
    assert f"| `{path.stem}` | `{scene.landscape}` | " in changed and "A new description \\| with a bar. |" in changed


def test_a_readme_without_the_markers_is_refused():
    table = _script("examples_table")
    with pytest.raises(ValueError, match="markers"):
        table.with_table("# RollBall\n")

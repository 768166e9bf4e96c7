"""The licence and the citation say the same as the package: LICENSE is the BSD 3-Clause text that
pyproject.toml names, and CITATION.cff cites the version rollball.__version__ says."""

import re
from pathlib import Path

import pytest

import rollball

ROOT = Path(__file__).resolve().parent.parent
CLAUSES = ("Redistributions of source code must retain the above copyright notice",
           "Redistributions in binary form must reproduce the above copyright notice",
           "Neither the name of the copyright holder nor the names of its",
           'THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS AND CONTRIBUTORS "AS IS"')


def _citation() -> dict[str, str]:
    """CITATION.cff's top-level keys with plain values (quotes removed)."""
    found = {}
    for line in (ROOT / "CITATION.cff").read_text(encoding="utf-8").splitlines():
        match = re.fullmatch(r"([a-z-]+):\s*(.*)", line)
        if match and match[2]:
            found[match[1]] = match[2].strip().strip("\"'")
    return found


def test_the_licence_in_pyproject_is_the_text_of_license():
    tomllib = pytest.importorskip("tomllib")   # (Python 3.11 and newer)
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert project["license"] == "BSD-3-Clause" and project["license-files"] == ["LICENSE"]
    assert text.startswith("BSD 3-Clause License\n") and all(clause in text for clause in CLAUSES)
    assert re.search(r"^Copyright \(c\) \d{4}, The RollBall developers$", text, re.MULTILINE)


def test_the_citation_cites_this_version_under_this_licence():
    citation = _citation()
    assert citation["cff-version"] == "1.2.0" and citation["title"] == "RollBall"
    assert citation["version"] == rollball.__version__
    assert citation["license"] == "BSD-3-Clause"
    assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", citation["date-released"])
    assert "- name: \"The RollBall developers\"" in (ROOT / "CITATION.cff").read_text(encoding="utf-8")

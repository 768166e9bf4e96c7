"""The docs' code blocks run. Every block of the README and the user guide (docs/guide/*.md):
Python blocks as they are written, ``.venv/bin/rollball`` commands with this Python; the few
commands that open the app's window or run the whole suite are listed in NOT_RUN with the reason,
and any other command fails here until it is run or listed. Of the other pages, the Python blocks
run and the JSON blocks (a scene file) load as scenes; their shell blocks (sweeps of 10⁵ runs, a
Dask cluster, benchmarks) and command synopses are not run."""

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NEWCOMER = [ROOT / "README.md", *sorted((ROOT / "docs" / "guide").glob("*.md"))]   # every block runs
# the manual's other hand-written pages (design.md's JSON blocks show other formats in part)
OTHERS = [*sorted((ROOT / "docs" / "reference").glob("*.md")), ROOT / "docs" / "performance.md",
          ROOT / "docs" / "maintainers.md"]
NOT_RUN = {
    "scripts/run": "opens the app's window and waits for its user (tests/gui drive the app)",
    "scripts/test": "runs the whole test suite (about 7 minutes), this test among it",
    ".venv/bin/rollball-app": "opens the app's window to record a video (tests/gui record one)",
}
FENCE = re.compile(r"^( *)```(\w*)\n(.*?)^\1```$", re.M | re.S)


def code_blocks():
    for document in NEWCOMER + OTHERS:
        text = document.read_text(encoding="utf-8")
        for match in FENCE.finditer(text):
            indent, language, code = match.groups()
            if document in OTHERS and language not in ("python", "json"):
                continue
            code = "".join(line[len(indent):] for line in code.splitlines(keepends=True))
            line = text.count("\n", 0, match.start()) + 1
            yield pytest.param(language, code, id=f"{document.relative_to(ROOT)}:{line}")


BLOCKS = list(code_blocks())


def test_the_blocks_are_found():
    languages = [block.values[0] for block in BLOCKS]
    assert languages.count("python") >= 4 and languages.count("sh") >= 5 and languages.count("json") >= 1
    assert set(languages) <= {"python", "sh", "json"}, "a block in another language: run it in this file"


@pytest.mark.parametrize("language, code", BLOCKS)
def test_the_code_block_runs(language, code, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)   # what a block writes (billiard.csv, hills.csv) lands here
    if language == "python":
        exec(compile(code, "<code block>", "exec"), {"__name__": "__doc_example__"})
        return
    if language == "json":
        from rollball import Scene

        assert Scene.loads(code).landscape
        return
    skipped = []
    for line in code.splitlines():
        argv = shlex.split(line, comments=True)
        if not argv:
            continue
        if argv[0] in NOT_RUN:
            skipped.append(f"{argv[0]}: {NOT_RUN[argv[0]]}")
            continue
        assert argv[0] == ".venv/bin/rollball", f"a command this test does not know: {line}"
        done = subprocess.run([sys.executable, "-m", "rollball", *argv[1:]], capture_output=True, text=True,
                              env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=300)
        assert done.returncode == 0, (line, done.stderr)
        assert done.stdout.strip(), line
    if skipped:
        pytest.skip("; ".join(skipped))

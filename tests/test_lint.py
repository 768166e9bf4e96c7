"""The code meets its linters, as pyproject.toml configures them: ruff (pyflakes, pycodestyle) finds
nothing, and lint-imports keeps every import contract (the core without the app or Qt, the kernel's
layers and its one way in, no import cycles)."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _run(command: list[str]) -> subprocess.CompletedProcess:
    # --no-cache: nothing written into the checkout (several test workers may run at once)
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)


def test_ruff_finds_nothing():
    result = _run([sys.executable, "-m", "ruff", "check", "--no-cache", "--output-format", "concise", "."])
    assert result.returncode == 0, result.stdout + result.stderr


def test_every_import_contract_is_kept():
    result = _run([str(Path(sys.executable).with_name("lint-imports")), "--no-cache"])
    assert result.returncode == 0, result.stdout + result.stderr
    assert "0 broken" in result.stdout

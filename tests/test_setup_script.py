"""scripts/setup: which optional groups an install brings, so that a later setup asking for one
of them (scripts/run's "app" after scripts/test's "test") does not run pip again."""

import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def groups_with_included(*groups: str) -> set[str]:
    """The shell function of scripts/setup, run on the project's pyproject.toml."""
    script = (ROOT / "scripts" / "setup").read_text()
    function = script[script.index("with_included() {"):script.index("\n}\n", script.index("with_included() {")) + 3]
    result = subprocess.run(["bash", "-c", function + 'with_included "$@"', "setup", *groups], cwd=ROOT,
                            capture_output=True, text=True, timeout=60, check=True)
    return set(result.stdout.split())


def test_the_test_group_includes_the_app_and_dask_groups():
    assert groups_with_included("test") == {"test", "app", "dask"}
    assert groups_with_included("app") == {"app"}
    assert groups_with_included("bench", "test") == {"bench", "test", "app", "dask"}
    assert groups_with_included() == set()

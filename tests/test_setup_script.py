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


def test_a_long_silent_step_says_every_few_seconds_that_it_is_still_at_work():
    """pip says nothing for a minute while it installs large wheels: the setup says it is at work."""
    script = (ROOT / "scripts" / "setup").read_text()
    start, end = script.index("say() {"), script.index("\n}\n", script.index("with_heartbeat() {")) + 3
    step = ("echo one; sleep 2.6; echo 'Requirement already satisfied: numpy'; echo 'ready rk4 mk'; "
            "echo two; exit $CODE")
    for code in (0, 3):
        result = subprocess.run(["bash", "-c", "set -euo pipefail\n" + script[start:end]
                                 + f'with_heartbeat "pip" bash -c "{step}"'],
                                capture_output=True, text=True, timeout=60,
                                env={"PATH": "/usr/bin:/bin", "ROLLBALL_SETUP_EVERY": "1", "CODE": str(code)})
        lines = result.stderr.splitlines()
        assert result.returncode == code
        assert lines[0] == "one" and lines[-1] == "two"
        assert 2 <= sum(line.startswith("rollball setup: pip: still at work") for line in lines) <= 3
        assert not any("Requirement" in line or line.startswith("ready") for line in lines)


def _checkout(tmp_path: Path) -> tuple[Path, Path]:
    """A copy of the scripts and pyproject.toml with a set-up .venv whose python only writes down
    how it was called (one line each, to the log returned); no system packages to install."""
    import hashlib
    import shutil

    root = tmp_path / "checkout"
    shutil.copytree(ROOT / "scripts", root / "scripts")
    shutil.copy(ROOT / "pyproject.toml", root / "pyproject.toml")
    (root / "scripts" / "system-deps").write_text("#!/usr/bin/env bash\nexit 0\n")
    log = tmp_path / "python.log"
    python = root / ".venv" / "bin" / "python"
    python.parent.mkdir(parents=True)
    python.write_text(f'#!/usr/bin/env bash\necho "$*" >> {log}\n')
    python.chmod(0o755)
    project = hashlib.sha256((root / "pyproject.toml").read_bytes()).hexdigest()
    (root / ".venv" / "rollball-installed").write_text(f"{project}\napp\n")
    log.write_text("")
    return root, log


def test_run_opens_the_app_without_the_setups_warm_up(tmp_path):
    """The app compiles the integrator in the background from launch: scripts/run does not wait
    for a warm-up of its own before the window (it took up to 12 s on a busy machine)."""
    root, log = _checkout(tmp_path)
    result = subprocess.run([str(root / "scripts" / "run"), "valley"], capture_output=True, text=True,
                            timeout=60, env={"PATH": "/usr/bin:/bin"})
    assert result.returncode == 0, result.stderr
    assert log.read_text().splitlines() == ["-m rollball_app valley"]
    assert result.stderr.splitlines()[-1] == "rollball: opening the app"


def test_setup_warms_up_unless_told_not_to(tmp_path):
    root, log = _checkout(tmp_path)
    for args, calls in ((["app"], ["-m rollball.warmup"]), (["--no-warm-up", "app"], [])):
        log.write_text("")
        result = subprocess.run([str(root / "scripts" / "setup"), *args], capture_output=True, text=True,
                                timeout=60, env={"PATH": "/usr/bin:/bin"})
        assert result.returncode == 0, result.stderr
        assert log.read_text().splitlines() == calls   # (pip not run: the stamp says "app" is installed)

"""scripts/setup: what an install brings (a dependency group such as "test", pip install --group;
an extra such as "app", pip install ".[app]"; and what each includes), so that a later setup asking
for one of them (scripts/run's "app" after scripts/test's "test") does not run pip again."""

import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SETUP = (ROOT / "scripts" / "setup").read_text()


def included(*names: str, cwd: Path = ROOT) -> set[tuple[str, str]]:
    """The shell function of scripts/setup, run on the pyproject.toml in ``cwd``: (kind, name) pairs."""
    function = SETUP[SETUP.index("with_included() {"):SETUP.index("\n}\n", SETUP.index("with_included() {")) + 3]
    result = subprocess.run(["bash", "-c", function + 'with_included "$@"', "setup", *names], cwd=cwd,
                            capture_output=True, text=True, timeout=60, check=True)
    return {tuple(line.split(" ", 1)) for line in result.stdout.splitlines()}


def test_the_test_group_includes_the_app_and_dask_extras():
    assert included("test") == {("group", "test"), ("group", "docs"), ("extra", "app"), ("extra", "dask")}
    assert included("app") == {("extra", "app")}
    assert included("dask", "app") == {("extra", "dask"), ("extra", "app")}
    assert included() == set()
    assert ("unknown", "bench") in included("bench", "test")


def test_a_group_listed_with_include_group_comes_along(tmp_path):
    """Another group (documentation tools, say) installs with "test" by one line in its list."""
    text = (ROOT / "pyproject.toml").read_text()
    text = text.replace("test = [\n", 'test = [\n    {include-group = "docs"},\n', 1)
    text = text.replace("[dependency-groups]\n", '[dependency-groups]\n'
                        'docs = ["mkdocs>=1.5", {include-group = "more"}]\n'
                        'more = [\n    "rollball[app]",  # a comment naming rollball[dask]\n]\n', 1)
    (tmp_path / "pyproject.toml").write_text(text)
    assert included("test", cwd=tmp_path) == {("group", "test"), ("group", "docs"), ("group", "more"),
                                             ("extra", "app"), ("extra", "dask")}
    assert included("docs", cwd=tmp_path) == {("group", "docs"), ("group", "more"), ("extra", "app")}


# A stand-in for .venv/bin/python that notes the commands it is given (pip installs, the warm-up)
FAKE_PYTHON = """#!/usr/bin/env bash
echo "$*" >> "$CALLS"
"""


CORE_IMPORTS = "-c import rollball.cli, rollball.simulation, rollball.comparison, rollball.sweeps, rollball.fitting"
APP_IMPORTS = ", rollball_app.main, rollball_app.window, rollball_app.compare_runs"


def _setup(folder: Path, *names: str) -> tuple[subprocess.CompletedProcess, list[str]]:
    calls = folder / "calls.txt"
    calls.write_text("")
    result = subprocess.run(["bash", "scripts/setup", *names], cwd=folder, capture_output=True, text=True,
                            timeout=60, env={**os.environ, "CALLS": str(calls)})
    return result, calls.read_text().splitlines()


def test_setup_installs_groups_with_pip_s_group_option_and_only_what_changed(tmp_path):
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "setup").write_text(SETUP)
    (tmp_path / "pyproject.toml").write_text((ROOT / "pyproject.toml").read_text())
    python = tmp_path / ".venv" / "bin" / "python"
    python.parent.mkdir(parents=True)
    python.write_text(FAKE_PYTHON)
    python.chmod(0o755)
    warm_up = "-m rollball.warmup"

    result, calls = _setup(tmp_path, "test")
    assert result.returncode == 0, result.stderr
    assert [call.split()[-1] for call in calls[:1]] == ["pip>=25.1"]   # pip reads groups from 25.1 on
    assert calls[1].startswith("-m pip install") and calls[1].endswith("--no-compile -e . --group test")
    # the bytecode of what RollBall and (with the test group) its app import, then the warm-up
    assert calls[2:] == [CORE_IMPORTS + APP_IMPORTS, warm_up]
    # the app and the Dask extras came with the test group: nothing more to install
    assert _setup(tmp_path, "app")[1] == [warm_up]
    assert _setup(tmp_path, "dask", "test")[1] == [warm_up]
    # an extra not installed yet: pip, for it alone (no group, so no newer pip needed)
    (tmp_path / ".venv" / "rollball-installed").write_text(
        (tmp_path / ".venv" / "rollball-installed").read_text().replace("extra dask\n", ""))
    result, calls = _setup(tmp_path, "dask")
    assert len(calls) == 3 and calls[0].endswith('--no-compile -e .[dask]') and calls[2] == warm_up
    assert calls[1] == CORE_IMPORTS + APP_IMPORTS   # (the app was installed before)
    # a changed pyproject.toml: installed again
    with open(tmp_path / "pyproject.toml", "a") as file:
        file.write("\n")
    assert _setup(tmp_path, "app")[1][-3:] == ["-m pip install --disable-pip-version-check --progress-bar off "
                                              "--no-compile -e .[app]", CORE_IMPORTS + APP_IMPORTS, warm_up]
    # the core alone: the core's bytecode
    (tmp_path / ".venv" / "rollball-installed").unlink()
    assert _setup(tmp_path)[1] == ["-m pip install --disable-pip-version-check --progress-bar off --no-compile -e .",
                                   CORE_IMPORTS, warm_up]


def test_setup_refuses_a_name_that_is_neither_a_group_nor_an_extra(tmp_path):
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "setup").write_text(SETUP)
    (tmp_path / "pyproject.toml").write_text((ROOT / "pyproject.toml").read_text())
    result, calls = _setup(tmp_path, "test", "bench")
    assert result.returncode == 2 and calls == [] and not (tmp_path / ".venv").exists()
    assert result.stderr.splitlines() == ["rollball setup: no dependency group or extra named bench in pyproject.toml"]


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
    (root / ".venv" / "rollball-installed").write_text(f"{project}\nextra app\n")
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

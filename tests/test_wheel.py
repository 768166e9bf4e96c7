"""The installed package carries its data: a wheel built from the sources holds the example
scenes, the app's icon and help pages (the top-level resources/ folder, installed as
rollball.resources), the benchmark's C source and the licence, installs the app (the top-level app/ folder)
as rollball_app and no top-level app, and lists the examples from any folder."""

import shutil
import subprocess
import sys
import zipfile

import pytest

from rollball.examples import example_names, example_tracks

ROOT = __import__("pathlib").Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    pytest.importorskip("setuptools", minversion="77")
    source = tmp_path_factory.mktemp("source")
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(ROOT / name, source)
    for package in ("rollball", "app", "resources"):
        shutil.copytree(ROOT / package, source / package,
                        ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    out = tmp_path_factory.mktemp("dist")
    result = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                             "--quiet", "-w", str(out), str(source)], capture_output=True, text=True,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    (path,) = out.glob("rollball-*.whl")
    return path


def test_wheel_holds_examples_icon_help_c_source_and_the_kernels_code(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    assert {f"rollball/resources/examples/{name}.json" for name in example_names()} <= names
    assert {f"rollball/resources/examples/{name}" for name in example_tracks()} <= names
    assert example_tracks() == ["billiard_track.csv"]
    assert len(example_names()) >= 10
    assert {"rollball/resources/__init__.py", "rollball/resources/icons/rollball.svg",
            "rollball/resources/help_pages/model.html", "rollball/resources/help_pages/plots.html",
            "rollball/bench/step.c", "rollball/examples.py", "rollball/kernel.bc",
            "rollball/kernel/interface.py", "rollball/kernel/loops.py",
            "rollball/kernel.json", "rollball_app/__init__.py", "rollball_app/__main__.py",
            "rollball_app/window.py"} <= names
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    entry_points = next(n for n in names if n.endswith(".dist-info/entry_points.txt"))
    text = zipfile.ZipFile(wheel).read(entry_points).decode()
    assert "rollball = rollball.cli:main" in text and "rollball-app = rollball_app:main" in text


def test_wheel_installs_no_top_level_app_or_resources(wheel):
    """Only rollball and rollball_app reach site-packages: nothing named app (or resources) to
    clash with another project's, or to be taken over by a local app/ folder."""
    tops = {name.split("/")[0] for name in zipfile.ZipFile(wheel).namelist()}
    assert {top for top in tops if not top.endswith(".dist-info")} == {"rollball", "rollball_app"}


def test_installed_wheel_lists_examples_from_any_folder(wheel, tmp_path):
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--quiet", "--target", str(target),
                    str(wheel)], check=True, capture_output=True, timeout=300)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "app").mkdir()   # a local app/ folder of someone else's: not what runs
    (elsewhere / "app" / "__init__.py").write_text("raise SystemExit('the wrong app')\n")
    code = ("import sys, rollball.cli; from rollball import resources; "
            "assert resources.path('icons', 'rollball.svg').is_file(); "
            "assert resources.path('help_pages', 'model.html').is_file(); "
            "assert resources.path('icons').is_relative_to(sys.argv[1]); "
            "import rollball_app; assert rollball_app.__file__.startswith(sys.argv[1]); "
            "sys.exit(rollball.cli.main(['examples']))")
    result = subprocess.run([sys.executable, "-c", code, str(target)], capture_output=True, text=True,
                            timeout=120, cwd=elsewhere, env={"PYTHONPATH": str(target), "PATH": "/usr/bin:/bin"})
    assert result.returncode == 0, result.stderr
    listed = [line.split()[0] for line in result.stdout.splitlines()[:len(example_names())]]
    assert listed == example_names()
    assert str(target) in result.stdout   # read from the installed copy, not this checkout


def test_installed_wheel_runs_on_its_shipped_kernel_code(wheel, tmp_path):
    from rollball import machine_code

    try:
        machine_code._shipped()
    except machine_code._Unusable as error:
        pytest.skip(f"the shipped code does not fit here ({error}): the wheel would compile its kernel with numba")
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--quiet", "--target", str(target),
                    str(wheel)], check=True, capture_output=True, timeout=300)
    code = ("import rollball; from rollball import machine_code, simulate, Scene; "
            "from rollball.examples import scene_path; "
            "traj = simulate(Scene.load(scene_path('bowl')), t_end=0.5); "
            "print(machine_code.source, traj.status, rollball.__file__)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                            cwd=tmp_path, env={"PYTHONPATH": str(target), "PATH": "/usr/bin:/bin",
                                               "ROLLBALL_CACHE_DIR": str(tmp_path / "cache")})
    assert result.returncode == 0, result.stderr
    source, status, where = result.stdout.split()
    assert (source, status) == ("shipped", "ok") and where.startswith(str(target))

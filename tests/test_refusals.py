"""Requests that would overflow, loop forever, corrupt a run or hide what went wrong are refused
with one clear line: in the Python API (ValueError/TypeError/RuntimeError) and on the command
line (exit 2, one line, no traceback)."""

import decimal
import errno
import os
import subprocess
import sys
import threading
import time
import warnings

import pytest
from conftest import make_scene

import rollball.landscape as landscape_module
from rollball import cache
from rollball import Scene, SceneError, Simulation, simulate
from rollball.cli import main
from rollball.examples import EXAMPLES_DIR

HILLS = str(EXAMPLES_DIR / "hills.json")


# -- the Python API ----------------------------------------------------------------------------------

@pytest.mark.parametrize("options, words", [
    (dict(t_end=1e300, dt=1e-10), "too many"),
    (dict(t_end=1e300, dt=1e-300), "too many"),
    (dict(t_end=10.0, dt=1e-20), "too many"),
    (dict(record_every=10**23), "record_every must be from 1"),
    (dict(record_every=2**63), "record_every must be from 1"),
    (dict(method="dopri5", record_dt=1e-300), "rows"),
    (dict(method="dopri5", t_end=1e300, record_dt=1e-10), "rows"),
    (dict(method="dopri5", rtol=1e-300), "rtol must be at least"),
    (dict(method="dopri5", atol=5e-324), "atol must be a normal positive float"),
    (dict(method="dopri5", dt=1e-20), "greater than 1e-13"),
    (dict(rtol=1e-6), "rtol and atol are for the adaptive method"),
    (dict(atol=1e-9), "rtol and atol are for the adaptive method"),
    (dict(method="dopri5", record_every=2), "record_every counts fixed steps"),
    (dict(dt=decimal.Decimal("NaN")), "finite"),
    (dict(dt="0.01"), "dt must be a number, not str"),
    (dict(dt=1j), "dt must be a number, not complex"),
])
def test_runs_that_cannot_be_done_are_refused_up_front(options, words):
    with pytest.raises(ValueError, match=words):
        Simulation(make_scene("x*y"), **options)


def test_a_decimal_is_a_number():
    traj = simulate(make_scene("0"), dt=decimal.Decimal("0.01"), t_end=decimal.Decimal("0.1"))
    assert traj.steps == 10
    scene = Scene(landscape="0", gravity=decimal.Decimal("9.81"))
    assert scene.gravity == 9.81 and type(scene.gravity) is float
    with pytest.raises(SceneError, match="gravity: must be a number, not a complex") as info:
        Scene(landscape="0", gravity=1 + 2j)
    assert info.value.key == "gravity" and info.value.reason == "must be a number, not a complex"


@pytest.mark.parametrize("steps", [0.5, 1.0, 0, -3, True, "10", None.__class__])
def test_advance_takes_a_whole_number_of_steps(steps):
    run = Simulation(make_scene("x*y"), t_end=0.01)
    with pytest.raises(ValueError, match="max_steps must be a whole number of 1 or more"):
        run.advance(steps)
    run.advance(3)
    assert run.steps == 3 and not run.done


def test_a_second_thread_advancing_the_same_run_gets_an_error():
    run = Simulation(make_scene("0.5*sin(x)*cos(y)", duration=1e4), dt=1e-4, record_every=1000)  # 1e8 steps
    worker = threading.Thread(target=run.advance)
    worker.start()
    try:
        deadline = time.monotonic() + 120
        while run.steps == 0 and time.monotonic() < deadline:  # the kernel is running
            time.sleep(0.001)
        with pytest.raises(RuntimeError, match="another thread"):
            run.advance(10)
    finally:
        run.cancel()
        worker.join()
    assert run.status.value == "aborted"


def test_simulate_takes_a_scene_or_its_path(tmp_path):
    assert simulate(HILLS, t_end=0.01).steps == 10
    with pytest.raises(TypeError, match="pass a Scene"):
        simulate({"landscape": "x"})
    with pytest.raises(FileNotFoundError):
        simulate(str(tmp_path / "missing.json"))


def test_a_full_cache_folder_compiles_without_it_and_says_so_once(monkeypatch):
    def full(path, data, keep=(), durable=True):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(cache, "atomic_write_bytes", full)
    monkeypatch.setattr(landscape_module, "_CACHE_BROKEN", False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        first = landscape_module.Landscape("0.25*x*y + 0.125").evaluate(2.0, 3.0)
        second = landscape_module.Landscape("0.375*x*y").evaluate(2.0, 3.0)
    assert first[0] == 1.625 and second[0] == 2.25 and second[1] == 1.125
    messages = [str(w.message) for w in caught if issubclass(w.category, landscape_module.CacheWarning)]
    assert len(messages) == 1 and "No space left on device" in messages[0]


# -- the command line ----------------------------------------------------------------------------------

def _one_line_error(capsys, code, args):
    try:
        returned = main(args)
    except SystemExit as e:  # usage errors end in argparse
        returned = e.code
    assert returned == code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("rollball") and err[0].isprintable(), err
    return err[0]


@pytest.mark.parametrize("args, words", [
    (["--t-end", "1e300", "--dt", "1e-300"], "too many"),
    (["--t-end", "1e300", "--dt", "1e-10"], "too many"),
    (["--every", str(10**23)], "record_every must be from 1"),
    (["--every", "9" * 5000], "number too large"),
    (["--method", "dopri5", "--record-dt", "1e-300"], "rows"),
    (["--method", "dopri5", "--rtol", "1e-300"], "rtol must be at least"),
    (["--method", "dopri5", "--dt", "1e-20"], "greater than 1e-13"),
    (["--rtol", "1e-8"], "rtol and atol are for the adaptive method"),
    (["--record-dt", "0.1"], "record_dt is for the adaptive methods"),
    (["--csv", ""], "empty file name"),
])
def test_command_line_refuses_bad_runs_with_exit_2(args, words, capsys):
    assert words in _one_line_error(capsys, 2, ["simulate", HILLS, *args])


def test_csv_minus_writes_to_standard_output(capsys):
    assert main(["simulate", HILLS, "--t-end", "0.01", "--csv", "-"]) == 0
    captured = capsys.readouterr()
    lines = captured.out.splitlines()
    assert lines[0].startswith("# program: rollball") and any(line.startswith("t,x,y,") for line in lines)
    assert len([line for line in lines if not line.startswith("#")]) == 1 + 11
    assert "10 steps" in captured.err and not os.path.exists("-")


def test_csv_onto_the_scene_being_run_is_refused_before_the_run(tmp_path, capsys):
    scene = tmp_path / "scene.json"
    scene.write_bytes(open(HILLS, "rb").read())
    before = scene.read_bytes()
    alias = tmp_path / "alias.csv"
    alias.symlink_to(scene)
    for target in (scene, alias):
        line = _one_line_error(capsys, 2, ["simulate", str(scene), "--csv", str(target)])
        assert "is the scene being run; nothing was written" in line
    assert scene.read_bytes() == before


@pytest.mark.parametrize("mode", [0o444, 0o555])
def test_csv_onto_a_read_only_file_is_refused(mode, tmp_path, capsys):
    out = tmp_path / "out.csv"
    out.write_text("keep me\n")
    os.chmod(out, mode)
    line = _one_line_error(capsys, 2, ["simulate", HILLS, "--t-end", "0.01", "--csv", str(out)])
    assert "read-only" in line and out.read_text() == "keep me\n"


def test_file_names_and_keys_are_escaped(tmp_path, capsys):
    name = tmp_path / "evil\n\x1b]0;title\x07.json"
    name.write_text('{"format": "rollball-scene", "version": 2, "landscape": "x", "\\u001b[2J\\nboom": 1}')
    line = _one_line_error(capsys, 2, ["simulate", str(name)])
    assert "\\x1b]0;title\\x07" in line and "'\\x1b[2J\\nboom': unknown key" in line


def test_numpy_warnings_do_not_break_the_summary_line(tmp_path, capsys):
    """A ball started where the landscape nearly overflows: derived columns hit inf."""
    scene = tmp_path / "steep.json"
    scene.write_text('{"format": "rollball-scene", "version": 2, "landscape": "exp(x)", '
                     '"start": {"x": 709.7}, "duration": 0.01}')
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a warning that got through would end the command
        code = main(["simulate", str(scene)])
    captured = capsys.readouterr()
    assert code in (0, 1, 2) and len((captured.out + captured.err).strip().splitlines()) == 1


def test_a_closed_pipe_ends_quietly():
    """rollball examples | head -1: the reader has gone before the program writes."""
    read, write = os.pipe()
    os.close(read)
    try:
        result = subprocess.run([sys.executable, "-m", "rollball", "examples"], stdout=write,
                                stderr=subprocess.PIPE, text=True, timeout=120)
    finally:
        os.close(write)
    assert result.returncode == 141 and result.stderr == ""

"""``rollball sweep`` hardened (issue 23): outputs checked before the first run, one set of files
all or nothing, a run whose values are refused is a row of its own (status invalid, the key and
value named) while the others run, and matplotlib's warnings stay out of the user's way."""

import csv
import json
import os

import pytest

from rollball.cli import main
from rollball.examples import EXAMPLES_DIR

HILLS = str(EXAMPLES_DIR / "hills.json")
FILES = ["sweep.csv", "sweep.json", "sweep.png"]


@pytest.fixture
def no_runs(monkeypatch):
    import rollball.sweeps

    def fail(*args, **kwargs):
        raise AssertionError("the runs started")

    monkeypatch.setattr(rollball.sweeps, "sweep", fail)


def rows(folder):
    with open(folder / "sweep.csv", encoding="utf-8") as stream:
        return list(csv.DictReader(stream))


@pytest.mark.parametrize("make", ["read_only_csv", "fifo_json", "out_is_a_file"])
def test_unwritable_outputs_are_refused_before_the_first_run(make, tmp_path, no_runs, capsys):
    out = tmp_path / "out"
    if make == "out_is_a_file":
        out.write_text("mine")
    else:
        out.mkdir()
        if make == "read_only_csv":
            (out / "sweep.csv").write_text("old")
            os.chmod(out / "sweep.csv", 0o444)
        else:
            os.mkfifo(out / "sweep.json")
    assert main(["sweep", HILLS, "--vary", "start.vx=0:1:4000", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert {"read_only_csv": "sweep.csv: is read-only", "fifo_json": "sweep.json: is a named pipe",
            "out_is_a_file": "is a file, not a folder"}[make] in err


def test_an_invalid_value_is_a_row_of_its_own_and_the_others_run(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["sweep", HILLS, "--vary", "integrator.dt=1e-300:1e-3:3", "--vary", "ball.radius=-0.1:0.1:2",
                 "--workers", "1", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "2 ok, 4 invalid" in captured.out and "warning" not in captured.err
    table = rows(out)
    assert [r["status"] for r in table] == ["invalid", "invalid", "invalid", "ok", "invalid", "ok"]
    assert "integrator.dt = 1e-300" in table[1]["message"] and "too many" in table[1]["message"]
    assert "ball.radius = -0.1" in table[2]["message"] and "greater than 0" in table[2]["message"]
    assert table[3]["t_reached"] == "10.0" and table[3]["message"] == ""


def test_all_runs_refused_draws_without_a_warning(tmp_path, capsys):
    assert main(["sweep", HILLS, "--vary", "ball.radius=-1:0:3", "--workers", "1", "--out", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert "3 invalid" in captured.out and "warning" not in captured.err.lower()
    assert sorted(os.listdir(tmp_path)) == FILES


def test_the_files_are_replaced_together_or_not_at_all(tmp_path, monkeypatch, capsys):
    from rollball.sweeps import table

    out = tmp_path / "out"
    assert main(["sweep", HILLS, "--vary", "start.vx=0:1:2", "--workers", "1", "--out", str(out)]) == 0
    old = {name: (out / name).read_bytes() for name in FILES}
    monkeypatch.setattr(table, "check", lambda directory, keep=(): None)  # turned read-only during the runs
    os.chmod(out / "sweep.png", 0o444)
    capsys.readouterr()
    assert main(["sweep", HILLS, "--vary", "start.vx=0:1:3", "--workers", "1", "--out", str(out)]) == 2
    (err,) = [line for line in capsys.readouterr().err.splitlines() if line.startswith("rollball:")]
    assert "sweep.png" in err and "none of sweep.csv, sweep.json, sweep.png was replaced" in err
    assert {name: (out / name).read_bytes() for name in FILES} == old
    (kept,) = [p for p in out.iterdir() if p.name.startswith("sweep-unsaved-")]
    assert str(kept) in err and sorted(os.listdir(kept)) == FILES and len(rows(kept)) == 3


def test_a_sweep_without_a_figure_removes_the_old_one(tmp_path, capsys):
    assert main(["sweep", HILLS, "--vary", "start.vx=0:1:2", "--workers", "1", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "sweep.png").exists()
    assert main(["sweep", HILLS, "--vary", "start.vx=0:1:2", "--vary", "start.vy=0:1:1", "--vary",
                 "start.spin=0:1:1", "--workers", "1", "--out", str(tmp_path)]) == 0
    assert sorted(os.listdir(tmp_path)) == ["sweep.csv", "sweep.json"]
    assert json.loads((tmp_path / "sweep.json").read_text())["grid"][2]["key"] == "start.spin"

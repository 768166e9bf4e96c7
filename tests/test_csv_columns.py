"""Model only what a scene needs, in the CSV too: a run that cannot change mode (the 2011 model:
friction null, glued after a lift-off; every version 1-2 scene) writes the columns written before
version 3, numbers only, so that ``numpy.loadtxt`` reads it as it always did; the mode columns
(mode, slip_speed, dissipated) appear only where the scene can change mode."""

import csv
import dataclasses

import numpy as np
import pytest

from conftest import GLUED, V2_EXAMPLES
from rollball import COLUMNS, Scene, read_csv, simulate
from rollball.cli import main
from rollball.scene import Contact
from rollball import trajectory as trajectories
from rollball.trajectory import MODES, UNITS

# What a CSV held before version 3 (the 23 columns and the energy error), and what it adds where
# the contact can change mode
OLD_COLUMNS = [*COLUMNS, "energy_error"]
MODE_COLUMNS = ["mode", "slip_speed", "dissipated"]
SLIDING = Contact(friction=0.3, restitution=0.0, after_liftoff="fly")


def header_lines(path) -> int:
    """How many lines come before the rows: the ``#`` lines and the header (what a script skips)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    return [line.startswith("#") for line in lines].index(False) + 1


def csv_header_and_rows(path):
    """The header and the rows as the csv module reads them, ``#`` lines left out."""
    with open(path, newline="", encoding="utf-8") as stream:
        rows = list(csv.reader(line for line in stream if not line.startswith("#")))
    return rows[0], rows[1:]


def units(path) -> list[str]:
    line = next(line for line in path.read_text(encoding="utf-8").splitlines() if line.startswith("# units: "))
    return line[len("# units: "):].split(",")


def loadtxt_as_version_2(path) -> np.ndarray:
    """How a script of version 2 read RollBall's CSV: numbers, comma-separated, after the header."""
    return np.loadtxt(path, delimiter=",", comments="#", skiprows=header_lines(path), ndmin=2)


def test_a_glued_scene_writes_the_columns_of_version_2_numbers_only(scene_factory, tmp_path):
    traj = simulate(scene_factory("0.5*sin(x)*cos(y)", x=0.3, vx=1.0, contact=GLUED), t_end=0.3)
    assert traj.modes is None and trajectories.csv_columns(traj) == tuple(OLD_COLUMNS)
    path = tmp_path / "glued.csv"
    traj.to_csv(path)
    table = loadtxt_as_version_2(path)
    assert table.dtype == float and table.shape == (len(traj), len(OLD_COLUMNS)) == (len(traj), 24)
    assert np.array_equal(table[:, :23], traj.data[:, :23])   # bit for bit
    assert np.array_equal(table[:, 23], traj.energy_error())
    header, rows = csv_header_and_rows(path)
    assert header == OLD_COLUMNS and all(len(row) == len(OLD_COLUMNS) for row in rows)
    assert units(path) == [UNITS[name] for name in OLD_COLUMNS]
    rows, extra = read_csv(path, extra=True)
    assert np.array_equal(rows, traj.data[:, :23]) and list(extra) == ["energy_error"]


def test_a_scene_that_can_slide_or_fly_writes_the_mode_columns(scene_factory, tmp_path):
    traj = simulate(scene_factory("0.5*sin(x)*cos(y)", x=0.3, vx=1.0, spin=3.0, contact=SLIDING), t_end=0.3)
    assert traj.modes is not None and trajectories.csv_columns(traj) == tuple(OLD_COLUMNS + MODE_COLUMNS)
    path = tmp_path / "sliding.csv"
    traj.to_csv(path)
    header, rows = csv_header_and_rows(path)
    assert header == OLD_COLUMNS + MODE_COLUMNS and len(rows) == len(traj)
    assert all(len(row) == len(header) for row in rows)
    assert units(path) == [UNITS[name] for name in header]
    modes = [row[header.index("mode")] for row in rows]
    assert set(modes) <= set(MODES) and modes == list(traj.mode)
    assert [float(row[header.index("dissipated")]) for row in rows] == list(traj.dissipated)
    numbers = np.loadtxt(path, delimiter=",", comments="#", skiprows=header_lines(path), usecols=range(24))
    assert np.array_equal(numbers[:, :23], traj.data[:, :23])
    assert list(read_csv(path, extra=True)[1]) == ["energy_error", *MODE_COLUMNS]


@pytest.mark.parametrize("contact, columns", [(GLUED, OLD_COLUMNS), (SLIDING, OLD_COLUMNS + MODE_COLUMNS),
                                              (Contact(None, 0.0, "fly"), OLD_COLUMNS + MODE_COLUMNS),
                                              (Contact(0.3, 0.0, "glued"), OLD_COLUMNS + MODE_COLUMNS)])
def test_an_empty_run_has_the_header_of_its_scene(scene_factory, tmp_path, contact, columns):
    traj = simulate(scene_factory("sqrt(x)", x=-1.0, contact=contact))
    assert len(traj) == 0
    path = tmp_path / "empty.csv"
    traj.to_csv(path)
    assert csv_header_and_rows(path) == (columns, []) and len(units(path)) == len(columns)


def test_the_trajectory_says_which_columns(scene_factory):
    traj = simulate(scene_factory("0*x", vx=0.5, contact=GLUED), t_end=0.01, record_every=5)
    assert trajectories.csv_columns(traj) == tuple(OLD_COLUMNS)
    modes = dataclasses.replace(traj, modes=np.zeros(len(traj), dtype=np.int8))
    assert trajectories.csv_columns(modes) == tuple(OLD_COLUMNS + MODE_COLUMNS)   # could change mode, even if it rolled


@pytest.mark.parametrize("name", ["bump", "cylinder", "liftoff"])
def test_a_version_2_example_gives_the_old_columns(tmp_path, capsys, name):
    scene = V2_EXAMPLES / f"{name}.json"
    assert Scene.load(scene).contact == GLUED   # what a version-2 file means
    out = tmp_path / f"{name}.csv"
    assert main(["simulate", str(scene), "--t-end", "0.2", "--csv", str(out)]) in (0, 1)
    header, rows = csv_header_and_rows(out)
    assert header == OLD_COLUMNS and rows
    table = loadtxt_as_version_2(out)
    assert table.shape == (len(rows), len(OLD_COLUMNS))
    assert units(out) == [UNITS[name] for name in OLD_COLUMNS]


def test_the_command_line_to_standard_output_follows_the_scene(tmp_path, capsys):
    assert main(["simulate", str(V2_EXAMPLES / "bump.json"), "--t-end", "0.05", "--csv", "-"]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if not line.startswith("#")]
    assert lines[0] == ",".join(OLD_COLUMNS) and all(len(line.split(",")) == 24 for line in lines[1:])
    flying = tmp_path / "flying.json"
    data = Scene.load(V2_EXAMPLES / "bump.json").to_dict()
    flying.write_text(Scene.from_dict({**data, "contact": {"friction": 0.3}}).dumps())
    assert main(["simulate", str(flying), "--t-end", "0.05", "--csv", "-"]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if not line.startswith("#")]
    assert lines[0] == ",".join(OLD_COLUMNS + MODE_COLUMNS)
    assert {line.split(",")[24] for line in lines[1:]} <= set(MODES)


def test_the_header_names_a_missing_friction_in_words(scene_factory, tmp_path):
    """A scene that flies but always rolls on the surface (friction null) says so, not "None"."""
    traj = simulate(scene_factory("0.5*sin(x)*cos(y)", x=0.3, vx=1.0,
                                  contact=Contact(friction=None, restitution=0.4, after_liftoff="fly")), t_end=0.1)
    path = tmp_path / "flies.csv"
    traj.to_csv(path)
    contact = next(line for line in path.read_text(encoding="utf-8").splitlines() if "restitution" in line)
    assert "friction none (it always rolls), restitution 0.4" in contact and "None" not in contact

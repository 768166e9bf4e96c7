"""A sweep's rest outcomes (scene version 4): rest_x, rest_y, rest_time from each run's "rest"
transition, basin from the steepest descent of the landscape there, the minima in sweep.json,
the basin map, and the same table on threads and on Dask."""

import csv
import dataclasses
import io
import json

import numpy as np
import pytest

from rollball import Scene, simulate, sweep
from rollball.cli import main

# A double well: minima (−1, 0) and (1, 0) at equal heights (numbered by x: 1 left, 2 right) and a
# saddle at (0, 0). Rolling resistance 0.05 holds a still ball where the slope is at most 0.05.
WELLS = Scene.from_dict({
    "format": "rollball-scene", "version": 4, "landscape": "(x**2 - 1)**2 + y**2",
    "contact": {"friction": 0.5, "rolling_resistance": 0.05}, "start": {"x": 1.004, "y": 0.0},
    "ball": {"radius": 0.05, "mass": 1.0}, "duration": 0.3, "view": {"min": -2.0, "max": 2.0, "step": 0.1}})
# started at rest: held at the start near either minimum and beside the saddle (slope 0.02 along y,
# or 0.04 along x), or rolling away from x = ±1.5
STARTS = {"start.x": [-1.5, -1.004, -0.997, 0.0, 0.01, 0.997, 1.004, 1.5], "start.y": [0.0, 0.01]}


@pytest.fixture(scope="module")
def table():
    return sweep(WELLS, STARTS, workers=2)


def test_the_rest_outcomes_are_the_rest_transitions(table):
    rested = 0
    for i, (x, y) in enumerate(zip(table["start.x"], table["start.y"])):
        traj = simulate(dataclasses.replace(WELLS, start=dataclasses.replace(WELLS.start, x=x, y=y)))
        rest = [change for change in traj.transitions if change.kind == "rest"]
        if rest:
            rested += 1
            assert (table["rest_x"][i], table["rest_y"][i], table["rest_time"][i]) == (rest[0].x, rest[0].y,
                                                                                          rest[0].time)
        else:
            assert np.isnan([table["rest_x"][i], table["rest_y"][i], table["rest_time"][i], table["basin"][i]]).all()
    assert rested == 12 and set(table["status"]) == {"ok"}


def test_a_resting_ball_is_in_the_basin_its_descent_reaches(table):
    basin = dict(zip(zip(table["start.x"], table["start.y"]), table["basin"]))
    assert [basin[x, 0.01] for x in (-1.004, -0.997, 0.01, 0.997, 1.004)] == [1, 1, 2, 2, 2]
    assert basin[-1.004, 0.0] == 1 and basin[1.004, 0.0] == 2
    # held on the line x = 0 beside the saddle: its descent ends on the saddle, in no minimum
    assert basin[0.0, 0.01] == 0 and basin[0.0, 0.0] == 0
    assert np.isnan(basin[1.5, 0.0]) and np.isnan(basin[-1.5, 0.01])   # rolling still: no rest, no basin
    assert [(m.number, m.x, m.y, m.f) for m in table.minima] == [(1, -1.0, 0.0, 0.0), (2, 1.0, 0.0, 0.0)]


def test_the_files_name_the_basins_and_list_the_minima(table, tmp_path):
    table.save(tmp_path, color="basin")
    rows = list(csv.DictReader(io.StringIO((tmp_path / "sweep.csv").read_text())))
    assert [r["basin"] for r in rows[:4]] == ["", "", "1", "1"]
    assert rows[0]["rest_x"] == "" and float(rows[2]["rest_x"]) == table["rest_x"][2]
    assert rows[2]["end_mode"] == "resting" and rows[0]["end_mode"] != "resting"
    info = json.loads((tmp_path / "sweep.json").read_text())
    assert info["minima"] == [{"number": 1, "x": -1.0, "y": 0.0, "f": 0.0}, {"number": 2, "x": 1.0, "y": 0.0, "f": 0.0}]
    assert "rest_x" in info["outcomes"] and "basin" in info["outcomes"]


def test_the_basin_map_has_a_colour_per_minimum(table, tmp_path):
    from matplotlib.image import imread

    from rollball.sweeps.plot import BASIN_COLOURS, BASIN_NONE, figure

    assert figure(table, tmp_path / "map.png", color="basin")
    pixels = {tuple(p) for p in (imread(tmp_path / "map.png")[..., :3] * 255).round().astype(int).reshape(-1, 3)}
    for colour in (BASIN_COLOURS[0], BASIN_COLOURS[1], BASIN_NONE):
        assert tuple(int(colour[k:k + 2], 16) for k in (1, 3, 5)) in pixels
    assert tuple(int(BASIN_COLOURS[2][k:k + 2], 16) for k in (1, 3, 5)) not in pixels   # two minima only


def test_the_basin_maps_title_sits_on_the_square_map_its_key_just_below():
    """start.x × start.y: a square map, the title's last line within a quarter inch above it (no
    white band between them), the key below the x axis' label as closely."""
    from rollball.sweeps.plot import _figure

    square = sweep(WELLS, {"start.x": [-1.004, 1.004], "start.y": [-1.004, 1.004]}, workers=1)
    fig = _figure(square, "basin")
    fig.canvas.draw()
    ax = fig.axes[0]
    [title] = [text for text in fig.texts if text.get_text() == fig.get_suptitle()]
    inch = fig.dpi
    drawn, heading = ax.get_window_extent(), title.get_window_extent()   # (the map as drawn: square)
    assert drawn.width == pytest.approx(drawn.height, rel=1e-3)
    assert 0.0 < (heading.y0 - drawn.y1) / inch < 0.25
    key, axis = ax.get_legend().get_window_extent(), ax.xaxis.get_tightbbox()
    assert 0.0 < (axis.y0 - key.y1) / inch < 0.25


def test_without_a_rest_there_are_no_minima():
    still = sweep(WELLS, {"start.x": [1.5]}, workers=1)
    assert still.minima is None and "minima" not in still.to_dict() and np.isnan(still["basin"]).all()


def test_a_sweep_over_a_parameter_of_the_landscape_leaves_the_basins_empty():
    scene = dataclasses.replace(WELLS, landscape="(x**2 - 1)**2 + y**2 + a*x", parameters={"a": 0.0})
    varied = sweep(scene, {"parameters.a": [0.0, 0.001], "start.x": [1.004]}, workers=1)
    assert np.isfinite(varied["rest_x"]).all() and np.isnan(varied["basin"]).all() and varied.minima is None


def test_the_command_line_colours_by_basin(tmp_path, capsys):
    path = tmp_path / "wells.json"
    WELLS.save(path)
    assert main(["sweep", str(path), "--vary", "start.x=0.995:1.005:3", "--vary", "start.y=-0.01:0.01:2",
                 "--color", "basin", "--workers", "2", "--out", str(tmp_path)]) == 0
    assert "6 ok" in capsys.readouterr().out
    assert [r["basin"] for r in csv.DictReader(open(tmp_path / "sweep.csv"))] == ["2"] * 6


def test_on_a_plane_the_rest_is_where_and_when_the_closed_form_puts_it():
    """Rolling from v₀ against rolling resistance c: at rest after 7v₀/(5cg) s and 7v₀²/(10cg) m;
    a plane has no minimum, so the basin is 0 (the steepest descent of a flat goes nowhere)."""
    c, g = 0.05, 9.81
    plane = Scene.from_dict({"format": "rollball-scene", "version": 4, "landscape": "0", "gravity": g,
                             "contact": {"friction": 0.5, "rolling_resistance": c}, "start": {"x": -1.0, "y": 0.0},
                             "duration": 5.0})
    v0 = np.array([0.5, 1.0, 1.5])
    table = sweep(plane, {"start.vx": v0}, workers=1)
    np.testing.assert_allclose(table["rest_time"], 7 * v0 / (5 * c * g), rtol=0, atol=1e-9)
    np.testing.assert_allclose(table["rest_x"], -1.0 + 7 * v0 ** 2 / (10 * c * g), rtol=0, atol=1e-9)
    assert (table["rest_y"] == 0.0).all() and (table["basin"] == 0.0).all() and table.minima == ()


def test_a_start_velocity_grid_is_coloured_by_basin_too(tmp_path):
    """Pushed left from the right well's bottom: slow starts stay in it, fast ones cross the saddle
    into the left well (spin friction ends the spin a stop leaves, so that each comes to rest)."""
    from rollball.sweeps.plot import figure

    scene = dataclasses.replace(WELLS, duration=20.0, contact=dataclasses.replace(WELLS.contact, spin_friction=0.05))
    table = sweep(scene, {"start.vx": [-0.2, -4.5], "start.vy": [0.0, 0.2]}, workers=2)
    assert table["basin"].reshape(2, 2).tolist() == [[2.0, 2.0], [1.0, 1.0]]
    assert figure(table, tmp_path / "velocity.png", color="basin")

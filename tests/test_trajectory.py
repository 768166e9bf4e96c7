"""Recording rules, chunked runs, the API's argument checks, and the CSV."""

import dataclasses

import numpy as np
import pytest

from rollball import COLUMNS, Simulation, Status, read_csv, simulate
from rollball.kernel.interface import ROW_SIZE
from rollball.run_size import step_count
from rollball.trajectory import DISSIPATED, ENERGY, Trajectory


def test_step_count():
    assert step_count(1e-3, 10.0) == 10000
    assert step_count(0.1, 0.3) == 3
    assert step_count(0.003, 0.01) == 4
    assert step_count(1.0, 0.25) == 1


def test_last_row_is_exactly_t_end_with_a_shortened_step(scene_factory):
    traj = simulate(scene_factory("0.1*x*y", x=0.2, vx=0.5), dt=0.003, t_end=0.01, record_every=3)
    assert traj.steps == 4
    assert traj.t[0] == 0.0 and traj.t[1] == pytest.approx(0.009, rel=1e-15) and traj.t[2] == 0.01


def test_record_every(scene_factory):
    traj = simulate(scene_factory("0.1*x*y", x=0.2, vx=0.5), dt=1e-3, t_end=1.0, record_every=10)
    assert len(traj) == 101
    assert traj.t[0] == 0 and traj.t[-1] == 1.0
    np.testing.assert_allclose(np.diff(traj.t), 0.01, rtol=1e-9)
    every_step = simulate(scene_factory("0.1*x*y", x=0.2, vx=0.5), dt=1e-3, t_end=1.0)
    assert np.array_equal(every_step.data[::10], traj.data)


def test_arrays_have_the_documented_shapes(scene_factory):
    traj = simulate(scene_factory("0.5*sin(x)*cos(y)"), t_end=0.1)
    n = len(traj)
    assert traj.t.shape == (n,) and traj.contact.shape == (n, 2)
    for name in ("center", "velocity", "omega"):
        assert getattr(traj, name).shape == (n, 3)
    assert traj.R.shape == (n, 3, 3)
    assert traj.energy.shape == traj.normal_force.shape == (n,)
    assert traj.status == "ok" and traj.liftoff_time is None


def test_chunked_run_equals_one_run_and_can_be_cancelled(scene_factory):
    scene = scene_factory("0.5*sin(x)*cos(y)", x=0.3, vx=1.0)
    whole = simulate(scene, t_end=1.0, record_every=7)
    run = Simulation(scene, t_end=1.0, record_every=7)
    chunks = []
    while not run.done:
        chunks.append(run.advance(33))
    assert np.array_equal(np.concatenate(chunks), whole.data)
    assert run.trajectory().status is Status.OK

    run = Simulation(scene, t_end=1.0)
    run.advance(100)
    run.cancel()
    traj = run.trajectory()
    assert traj.status is Status.ABORTED and traj.steps == 100 and len(traj) == 101
    assert "stopped" in traj.message
    assert len(run.advance(10)) == 0


@pytest.mark.parametrize("name", ["hills", "ridge_jump"])   # (one kernel run; a run that flies and lands)
def test_rows_are_handed_back_as_copies_or_not_at_all(name):
    """``advance`` returns the new rows as an array of the caller's own; with ``rows=False``
    nothing, and the run records the same rows, chunk by chunk or at once."""
    from rollball.examples import scene_path
    from rollball.scene import Scene

    scene = Scene.load(scene_path(name))
    whole = Simulation(scene, t_end=0.8)
    returned = whole.advance()
    assert np.array_equal(returned, whole.rows) and len(returned) > 100
    returned[:] = np.nan   # (the caller's own: the run's rows are untouched)
    assert np.isfinite(whole.rows).all()
    quiet = Simulation(scene, t_end=0.8)
    while not quiet.done:
        assert quiet.advance(57, rows=False) is None
    assert np.array_equal(quiet.rows, whole.rows)
    assert np.array_equal(quiet.trajectory().data, whole.trajectory().data)


@pytest.mark.parametrize("kwargs, message", [
    (dict(dt=0), "dt"), (dict(dt=-1e-3), "dt"), (dict(dt=float("nan")), "dt"), (dict(dt="1e-3"), "dt"),
    (dict(t_end=float("inf")), "t_end"), (dict(t_end=0), "t_end"),
    (dict(record_every=0), "record_every"), (dict(record_every=1.5), "record_every"),
    (dict(record_every=True), "record_every"),
    (dict(method="rk45"), "valid methods"), (dict(munthe_kaas="yes"), "munthe_kaas"),
    (dict(dt=1e-9, t_end=10.0), "rows"),
])
def test_bad_arguments_are_refused(scene_factory, kwargs, message):
    with pytest.raises(ValueError, match=message):
        simulate(scene_factory("x"), **kwargs)


def test_csv_round_trip_at_full_precision(scene_factory, tmp_path):
    traj = simulate(scene_factory("0.5*sin(x)*cos(y)", x=0.3, vx=1.0, spin=1 / 3), t_end=0.5)
    path = tmp_path / "out.csv"
    traj.to_csv(path)
    lines = path.read_text().splitlines()
    header = [line for line in lines if not line.startswith("#")][0]
    # the 2011 model cannot change mode: no mode columns (tests/test_csv_columns.py)
    assert header == ",".join(COLUMNS) + ",energy_error" and " " not in header
    assert any(line.startswith("# landscape: 0.5*sin(x)*cos(y)") for line in lines)
    back = read_csv(path)
    assert back.shape == (len(traj), 23)
    assert np.array_equal(back, traj.data[:, :23])  # bit for bit
    rows, extra = read_csv(path, extra=True)
    assert np.array_equal(rows, back) and list(extra) == ["energy_error"]
    assert np.array_equal(extra["energy_error"], traj.energy_error())
    # a run that could change mode (here: it rolled throughout) writes them too, and they read back
    dataclasses.replace(traj, modes=np.zeros(len(traj), dtype=np.int8)).to_csv(path)
    rows, extra = read_csv(path, extra=True)
    assert np.array_equal(rows, back) and list(extra) == ["energy_error", "mode", "slip_speed", "dissipated"]
    assert list(extra["mode"]) == ["rolling"] * len(traj)
    assert np.array_equal(extra["slip_speed"], traj.slip_speed) and np.array_equal(extra["dissipated"], traj.dissipated)
    assert np.array_equal(extra["energy_error"], traj.energy_error())


def test_csv_says_every_unit_and_each_rows_energy_error(scene_factory, tmp_path):
    scene = scene_factory("0.5*sin(x)*cos(y)", x=0.3, vx=1.0)
    traj = simulate(scene, method="euler", dt=0.01, t_end=1.0)
    path = tmp_path / "out.csv"
    dataclasses.replace(traj, modes=np.zeros(len(traj), dtype=np.int8)).to_csv(path)   # with the mode columns
    lines = path.read_text().splitlines()
    names = lines[[not line.startswith("#") for line in lines].index(True)].split(",")
    units = next(line for line in lines if line.startswith("# units: "))[len("# units: "):].split(",")
    assert len(units) == len(names) == 27
    unit = dict(zip(names, units))
    assert [unit[k] for k in ("t", "x", "cz", "vx", "wz", "r23", "energy", "normal_force", "energy_error", "mode",
                              "slip_speed", "dissipated")] == ["s", "m", "m", "m/s", "rad/s", "1", "J", "N", "1", "-",
                                                               "m/s", "J"]
    table = np.loadtxt(path, delimiter=",", comments="#", skiprows=lines.index(",".join(names)) + 1,
                       usecols=range(24))
    energy = table[:, names.index("energy")]
    scale = max(abs(energy[0]), scene.ball.mass * scene.gravity * scene.ball.radius)
    np.testing.assert_allclose(table[:, 23], (energy - energy[0]) / scale, rtol=1e-15, atol=0)
    assert abs(table[-1, 23]) > 1e-6  # Euler at this step visibly changes the energy


def test_csv_without_the_extra_columns_still_reads(scene_factory, tmp_path):
    traj = simulate(scene_factory("0.1*x*y", vx=0.5), t_end=0.1)
    path = tmp_path / "old.csv"
    rows = "\n".join(",".join(repr(float(v)) for v in row) for row in traj.data)
    path.write_text("# program: rollball 0.1.0\n" + ",".join(COLUMNS) + "\n" + rows + "\n")
    assert np.array_equal(read_csv(path), traj.data[:, :23])
    assert read_csv(path, extra=True)[1] == {}


def test_csv_of_an_empty_trajectory_has_the_header(scene_factory, tmp_path):
    traj = simulate(scene_factory("sqrt(x)", x=-1.0))
    assert len(traj) == 0
    path = tmp_path / "empty.csv"
    traj.to_csv(path)
    assert [line for line in path.read_text().splitlines() if not line.startswith("#")] == [
        ",".join(COLUMNS) + ",energy_error"]   # the 2011 model's columns (tests/test_csv_columns.py)
    assert read_csv(path).shape == (0, 23)


def test_columns_are_consistent(scene_factory):
    scene = scene_factory("0.5*sin(x)*cos(y)", x=0.3, vx=1.0, spin=2.0)
    traj = simulate(scene, t_end=0.5)
    landscape = scene.landscape
    from rollball.landscape import landscape_for

    f, fx, fy = landscape_for(landscape).evaluate(traj.contact[:, 0], traj.contact[:, 1])[:3]
    N = np.stack([-fx, -fy, np.ones_like(fx)], axis=1) / np.sqrt(1 + fx**2 + fy**2)[:, None]
    r = scene.ball.radius
    np.testing.assert_allclose(traj.center, np.column_stack([traj.contact, f]) + r * N, atol=1e-14)
    np.testing.assert_allclose(traj.velocity, r * np.cross(traj.omega, N), atol=1e-13)
    np.testing.assert_allclose(np.einsum("ij,ij->i", traj.velocity, N), 0, atol=1e-13)
    kinetic = 0.5 * np.sum(traj.velocity**2, 1) + 0.5 * 0.4 * r**2 * np.sum(traj.omega**2, 1)
    np.testing.assert_allclose(traj.energy, kinetic + 9.81 * traj.center[:, 2], rtol=1e-13)
    # the centre velocity column is the time derivative of the centre column
    dc = np.gradient(traj.center, traj.t, axis=0)[1:-1]
    np.testing.assert_allclose(dc, traj.velocity[1:-1], atol=1e-5)


def test_cancel_from_another_thread_stops_a_long_advance(scene_factory):
    import threading
    import time

    run = Simulation(scene_factory("0.5*sin(x)*cos(y)", x=0.3), dt=1e-5, t_end=1e4, record_every=10**5)
    run.advance(1)  # compiled and started
    worker = threading.Thread(target=run.advance)
    worker.start()
    time.sleep(0.2)
    start = time.perf_counter()
    run.cancel()
    worker.join(timeout=30)
    assert not worker.is_alive()
    assert time.perf_counter() - start < 10
    assert run.status is Status.ABORTED and 0 < run.steps < run.n_steps


def test_named_slices_are_the_csv_columns():
    from rollball import trajectory as layout

    assert COLUMNS[layout.T] == "t"
    for name, columns in (("CONTACT", "x y"), ("CENTER", "cx cy cz"), ("VELOCITY", "vx vy vz"),
                          ("OMEGA", "wx wy wz"), ("R", "r11 r12 r13 r21 r22 r23 r31 r32 r33")):
        assert COLUMNS[getattr(layout, name)] == tuple(columns.split())
    assert (COLUMNS[layout.ENERGY], COLUMNS[layout.NORMAL_FORCE]) == ("energy", "normal_force")


def test_warnings_name_energy_and_orientation_errors(scene_factory):
    scene = scene_factory("0.5*sin(x)*cos(y)", x=0.3, y=-0.2)
    good = simulate(scene, method="rk4", dt=1e-3, t_end=1.0)
    assert good.warnings() == []
    classic = simulate(scene, method="euler", munthe_kaas=False, dt=0.01, t_end=3.0)
    notes = classic.warnings()
    assert len(notes) == 2
    assert "energy changed by" in notes[0] and "R is no longer a rotation" in notes[1]
    assert float(notes[1].split("= ")[1].split(":")[0]) == pytest.approx(classic.orthogonality_error()[-1], rel=0.05)


def test_recording_keeps_a_displayed_run_small(scene_factory):
    from rollball.simulation import ADAPTIVE_ROWS, AUTO_ROWS, recording

    scene = scene_factory("0.1*x*y", x=0.2, vx=0.5)
    assert recording(scene, dt=1e-3, t_end=10.0) == {"record_every": 1}
    assert recording(scene, dt=1e-5, t_end=10.0) == {"record_every": 1_000_000 // AUTO_ROWS}
    assert recording(scene, dt=1e-5, t_end=10.0, record_every=7) == {"record_every": 7}
    assert recording(scene, method="adaptive", t_end=2.0) == {"record_dt": 2.0 / ADAPTIVE_ROWS}


def test_modes_and_transitions_reach_the_csv(scene_factory, tmp_path):
    from rollball.trajectory import Transition

    traj = simulate(scene_factory("0*x", vx=0.5), t_end=0.01, record_every=5)
    flown = dataclasses.replace(traj, modes=np.array([0, 2, 1], dtype=np.int8),
                                transitions=(Transition(0.004, "liftoff", 0.1, 0.0),
                                             Transition(0.007, "landing", 0.2, 0.0, 0.5, 0.01)))
    assert list(flown.mode) == ["rolling", "flying", "sliding"] and flown.landings == 1
    assert "0.5 m/s along the normal, 0.01 J lost" in flown.transitions[1].sentence()
    path = tmp_path / "modes.csv"
    flown.to_csv(path)
    assert list(read_csv(path, extra=True)[1]["mode"]) == ["rolling", "flying", "sliding"]


def test_the_energy_drift_is_the_largest_energy_error_to_the_last_bit():
    """``energy_drift`` (from the largest and smallest E + D) is the largest size of
    ``energy_error`` (every row's), bit for bit, NaN where a row is NaN or an infinity cancels,
    on random columns of every scale and with infinities, the first row's too."""
    rng = np.random.default_rng(0)
    for trial in range(2000):
        n = int(rng.integers(1, 30))
        data = np.zeros((n, ROW_SIZE))
        data[:, ENERGY] = rng.normal(size=n) * 10 ** rng.uniform(-3, 3)
        data[:, DISSIPATED] = rng.normal(size=n) * 10 ** rng.uniform(-3, 3)
        if trial % 7 == 0:
            data[rng.integers(n), ENERGY] = rng.choice([np.nan, np.inf, -np.inf])
        if trial % 11 == 0:
            data[0, ENERGY] = rng.choice([np.nan, np.inf, -np.inf])
        traj = Trajectory(data)
        with np.errstate(invalid="ignore"):
            drift, every = traj.energy_drift, float(np.max(np.abs(traj.energy_error())))
        assert drift == every or (np.isnan(drift) and np.isnan(every)), (trial, drift, every)

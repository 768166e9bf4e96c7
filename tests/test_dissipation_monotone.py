"""The energy each cause takes only grows: over every row interval, the rolling resistance's and
the spin friction's cumulative dissipation never fall by more than round-off, for every method
(fixed steps and the adaptive pairs) on a plane, an incline the ball rolls back down (ω_t through
0 at the turning point) and the three wells (docs/design.md §1, "Dissipation"). A fall means a
couple pushed along the motion and the ball gained energy from it, which E + ΣD cannot show."""

import dataclasses
import functools

import numpy as np
import pytest

from rollball.examples import EXAMPLES_DIR
from rollball.scene import Ball, Contact, Integrator, Scene, Start
from rollball.simulation import simulate

# (method, dt or rtol)
RUNS = [("rk4", 0.002), ("lawson5", 0.002), ("gauss4", 0.002), ("dopri5", 1e-6), ("dopri5", 1e-9),
        ("dop853", 1e-6), ("dop853", 1e-9)]
ROUND_OFF = 1e-12   # of the run's energy scale


def _integrator(method, step):
    if method in ("dopri5", "dop853"):
        return Integrator(method=method, dt=1e-3, rtol=step, atol=step * 1e-3)
    return Integrator(method=method, dt=step)


def _plane(integrator):
    """Rolling at 1.5 m/s and spinning at 40 rad/s about N: the rolling stops first, then the spin."""
    return Scene(landscape="0*x", gravity=9.81, ball=Ball(radius=0.1, mass=2.0), start=Start(x=0.0, y=0.0, vx=1.5,
                 spin=40.0), contact=Contact(friction=0.3, rolling_resistance=0.05, spin_friction=0.02),
                 duration=12.0, integrator=integrator)


def _incline(integrator):
    """Sent up a slope of tan θ = 0.04 > c_rr = 0.02: it stops for an instant and rolls back down."""
    return Scene(landscape="0.04*x", gravity=9.81, ball=Ball(radius=0.1, mass=2.0), start=Start(x=0.0, y=0.0, vx=1.5),
                 contact=Contact(friction=0.3, rolling_resistance=0.02), duration=6.0, integrator=integrator)


def _wells(integrator):
    """Three wells (c_rr 0.04, μ_s 0.05), started at rest: a 16 s path to rest over turning points."""
    scene = Scene.load(EXAMPLES_DIR / "wells.json")
    return dataclasses.replace(scene, integrator=integrator)


@functools.lru_cache(maxsize=None)
def _run(scene, method, step):
    return simulate({"plane": _plane, "incline": _incline, "wells": _wells}[scene](_integrator(method, step)))


def _largest_fall(traj, cause):
    return -min(0.0, float(np.diff(traj.dissipated_by[cause]).min())) / traj.energy_scale


@pytest.mark.parametrize("scene", ["plane", "incline", "wells"])
@pytest.mark.parametrize("method, step", RUNS)
def test_the_rolling_resistance_never_gives_energy_back(scene, method, step):
    traj = _run(scene, method, step)
    assert str(traj.status) == "ok"
    assert _largest_fall(traj, "rolling") <= ROUND_OFF, traj.t[np.argmin(np.diff(traj.dissipated_by["rolling"]))]


@pytest.mark.parametrize("scene", ["plane", "incline", "wells"])
@pytest.mark.parametrize("method, step", RUNS)
def test_the_spin_friction_never_gives_energy_back(scene, method, step):
    """(on the wells the pairs' steps once crossed a static spin couple's limit, a kink of its law, and
    lost up to 4.5e-7 J in a row: docs/design.md §1, "Dissipation")"""
    traj = _run(scene, method, step)
    assert _largest_fall(traj, "spin") <= ROUND_OFF, traj.t[np.argmin(np.diff(traj.dissipated_by["spin"]))]

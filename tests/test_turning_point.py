"""The stiffness check's shortcut (``kernel.loops.far_from_turning``): where it says ω_t is surely
not at a turning point, ``physics.turning_point`` says so too, for lines t + r τ of every scale
and direction, and near its bound (docs/design.md §1, "Dissipation")."""

import numpy as np

from rollball.kernel.loops import far_from_turning
from rollball.kernel.physics import TURN_TIME, turning_point


def _cases(count, seed):
    rng = np.random.default_rng(seed)
    t = rng.normal(size=(count, 3)) * 10.0 ** rng.uniform(-8, 4, size=(count, 1))
    r = rng.normal(size=(count, 3))
    r *= np.linalg.norm(t, axis=1, keepdims=True) / np.linalg.norm(r, axis=1, keepdims=True)
    r *= 10.0 ** rng.uniform(-3, 3, size=(count, 1))   # |r| / |t| from 1e-3 to 1e3 (1/s)
    # half of them towards 0: r against t with a little sideways, passing 0 about where the step ends
    half = count // 2
    side = rng.normal(size=(half, 3)) * np.linalg.norm(r[:half], axis=1, keepdims=True)
    r[:half] = -t[:half] * (np.linalg.norm(r[:half], axis=1) / np.linalg.norm(t[:half], axis=1))[:, None] \
        + side * 10.0 ** rng.uniform(-4, 0, size=(half, 1))
    unit = 10.0 ** rng.uniform(-3, 0, size=count)
    h = unit * 10.0 ** rng.uniform(-3, 0.5, size=count)
    h[:half] = np.linalg.norm(t[:half], axis=1) / np.linalg.norm(r[:half], axis=1) * rng.uniform(0.3, 3.0, size=half)
    cap = np.linalg.norm(r, axis=1) * 10.0 ** rng.uniform(-3, 1, size=count)
    return t, r, unit, h, cap


def test_where_the_shortcut_rules_a_turning_point_out_there_is_none():
    far_ = far_from_turning.py_func
    turning = turning_point.py_func
    t, r, unit, h, cap = _cases(20_000, 7)
    ruled_out = stiff = 0
    for (t1, t2, t3), (r1, r2, r3), u, step, c in zip(t, r, unit, h, cap):
        far = far_(t1 * t1 + t2 * t2 + t3 * t3, r1 * r1 + r2 * r2 + r3 * r3, u, step)
        is_turning = turning(t1, t2, t3, r1, r2, r3, c, u, step)
        assert not (far and is_turning), (t1, t2, t3, r1, r2, r3, u, step)
        ruled_out += far
        stiff += is_turning
    assert ruled_out > 5_000 and stiff > 2_000, (ruled_out, stiff)   # (both sides of the bound are tried)


def test_the_shortcut_rules_out_a_slow_turn_and_not_a_fast_one():
    unit = 0.125   # (binary fractions: the bound met exactly, |r| TURN_TIME unit = |t| / 4)
    rate = 1.0 / (4.0 * TURN_TIME * unit)
    h = 0.25 / rate   # |r| h = |t| / 4, within the reach's bound |t| / 3
    assert far_from_turning.py_func(1.0, rate * rate, unit, h)
    assert not far_from_turning.py_func(1.0, (1.01 * rate) ** 2, unit, h)   # (a little faster: judged in full)
    assert not far_from_turning.py_func(1.0, rate * rate, unit, 0.34 / rate)   # (a longer reach: in full)
    assert not far_from_turning.py_func(float("nan"), 1.0, unit, h)
    assert not far_from_turning.py_func(1.0, 1.0, float("inf"), h)

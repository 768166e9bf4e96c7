"""The 2011 model stays exactly as it was: with the contact's defaults (friction None = always
enough to roll, "glued" after a lift-off) every method gives the same rows, bit for bit, as the
kernel before friction and lift-off stops existed (their SHA-256 recorded in
tests/data/rows_before_contact.json by ``python tests/test_contact_defaults.py --record`` with
that kernel; the adaptive pairs' four re-recorded once their error scale changed, kernel.steps.error_norm,
with nothing else in the kernel changed), and a run whose parameters name the defaults explicitly is the
same run."""

import hashlib
import json
import platform
import sys
from pathlib import Path

import numpy as np
import pytest

from rollball import kernel
from rollball.examples import example_scenes
from rollball.scene import Scene
from rollball.simulation import Simulation

DATA = Path(__file__).parent / "data" / "rows_before_contact.json"
# (example, method, munthe_kaas, t_end): every stepping path, on a scene with a lift-off (cylinder,
# at 1.45 s) and one without
CASES = [(name, method, mk, t_end) for name, t_end in (("cylinder", 1.6), ("hills", 0.6))
         for method, mk in (("euler", True), ("rk4", True), ("rk4", False), ("lawson5", True),
                            ("lawson5", False), ("gauss4", True), ("gauss6", True), ("dopri5", True),
                            ("dop853", True))]
SCENES = {path.stem: scene for path, scene in example_scenes()}
# (the cylinder as shipped in version 2, before it stood on a floor and flew)
SCENES["cylinder"] = Scene.load(Path(__file__).parent / "data" / "examples_v2" / "cylinder.json")


def _run(name, method, mk, t_end, p=None):
    run = Simulation(SCENES[name], method=method, munthe_kaas=mk, t_end=t_end)
    if p is not None:
        run._p[:] = p(run._p)
    run.advance()
    rows = np.ascontiguousarray(run.rows[:, :23])  # (the 2011 model's columns)
    return run, hashlib.sha256(rows.tobytes()).hexdigest()


def _key(case):
    return "{} {} {} {}".format(*case)


@pytest.mark.skipif(platform.machine() not in ("x86_64", "AMD64"), reason="digests recorded on x86-64")
@pytest.mark.parametrize("case", CASES, ids=_key)
def test_defaults_give_the_rows_of_before(case):
    run, digest = _run(*case)
    assert digest == json.loads(DATA.read_text())[_key(case)]
    assert run.status.value == "ok"


def test_explicit_defaults_are_the_defaults():
    r, m, g = 0.1, 1.0, 9.81
    plain = kernel.parameters(r, m, g)
    named = kernel.parameters(r, m, g, 0.0, friction=None, fly=False, dissipated=0.0)
    assert np.array_equal(plain, named)
    assert plain[kernel.P_MU] == np.inf and plain[kernel.P_FLY] == 0.0


@pytest.mark.parametrize("gravity", [9.81, -3.7, 0.0])
def test_one_runs_parameters_are_a_sweeps_column(gravity):
    """A run's parameters (floats: the quick path) are the numbers a sweep's column of them gives
    (arrays), bit for bit, with every option set (and without gravity: the time unit inf)."""
    options = dict(friction=0.3, fly=True, dissipated=0.25, stiff=True, rolling_resistance=0.01, spin_friction=0.02,
                   air=1e-3, causes=(0.1, 0.05, 0.1))
    for args, kw in (((0.1, 1.3, gravity, 1e-8), options), ((0.1, 1.3, gravity), {})):
        one = kernel.parameters(*args, **kw)
        column = kernel.parameters(*(np.array([a, a]) for a in args), **kw)
        assert one.dtype == column.dtype and np.array_equal(one, column[:, 0])


if __name__ == "__main__" and sys.argv[1:] == ["--record"]:
    DATA.write_text(json.dumps({_key(case): _run(*case)[1] for case in CASES}, indent=1) + "\n")

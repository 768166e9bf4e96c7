"""Named parameters (scene version 3): screened names, files, the migration from version 2,
values as arguments of one compiled landscape, and sweeps over them (docs/design.md §4)."""

import json

import numpy as np
import pytest

from rollball import Scene, simulate
from rollball.examples import EXAMPLES_DIR
from rollball.kernel import KERNEL_STATUSES
from rollball.formula import MAX_PARAMETERS, FormulaError, parse_formula
from rollball.landscape import _COMPILED, landscape_of
from rollball.scene import VERSION, Parameter, SceneError
from rollball.sweeps import Grid, sweep

V3 = {"format": "rollball-scene", "version": 3, "landscape": "a*sin(k*x)*cos(y)",
      "parameters": {"a": 0.5, "k": {"value": 1.0, "min": 0.5, "max": 4.0}}}


def test_a_parameter_is_a_number_or_a_value_with_a_range():
    scene = Scene.from_dict(V3)
    assert scene.parameters == (Parameter("a", 0.5), Parameter("k", 1.0, 0.5, 4.0))
    assert scene.parameter_names == ("a", "k") and scene.parameter_values == (0.5, 1.0)
    assert Scene(landscape="a*x", parameters={"a": 2}).parameters == (Parameter("a", 2.0),)


def test_files_are_written_as_version_3_with_parameters_as_given(tmp_path):
    scene = Scene.from_dict(V3)
    path = tmp_path / "p.json"
    scene.save(path)
    saved = json.loads(path.read_text(encoding="utf-8"))
    assert saved["version"] == VERSION and saved["parameters"] == V3["parameters"]
    assert list(saved)[:4] == ["format", "version", "landscape", "parameters"]
    assert Scene.load(path) == scene
    plain = Scene.load(EXAMPLES_DIR / "hills.json")   # a version-2 file: written as version 3, no parameters
    assert plain.to_dict()["version"] == VERSION and "parameters" not in plain.to_dict()


@pytest.mark.parametrize("parameters, key, fragment", [
    ({"x": 1.0}, "parameters.x", "taken by the formula's own variables"),
    ({"pi": 1.0}, "parameters.pi", "taken by the formula's own constants"),
    ({"e": 1.0}, "parameters.e", "constants"),
    ({"sin": 1.0}, "parameters.sin", "the name of a function"),
    ({"max": 1.0}, "parameters.max", "the name of a function"),
    ({"_a": 1.0}, "parameters", "identifier"),
    ({"__import__": 1.0}, "parameters", "identifier"),
    ({"a b": 1.0}, "parameters", "identifier"),
    ({"ä": 1.0}, "parameters", "identifier"),
    ({"": 1.0}, "parameters", "identifier"),
    ({"a" * 33: 1.0}, "parameters", "at most 32 characters"),
    ({f"p{i}": 1.0 for i in range(MAX_PARAMETERS + 1)}, "parameters", f"at most {MAX_PARAMETERS} parameters"),
    ({"a": True}, "parameters.a", "must be a number"),
    ({"a": "1"}, "parameters.a", "must be a number"),
    ({"a": None}, "parameters.a", "must be a number"),
    ({"a": {"min": 0, "max": 1}}, "parameters.a.value", "missing"),
    ({"a": {"value": 1, "min": 0}}, "parameters.a.max", "missing"),
    ({"a": {"value": 1, "min": 2, "max": 1}}, "parameters.a.min", "must be less than max"),
    ({"a": {"value": 1, "step": 2}}, "parameters.a.step", "unknown key"),
    ({"a": {"value": 1e400}}, "parameters.a.value", "finite"),
    ([1, 2], "parameters", "must be an object"),
])
def test_bad_parameters_are_refused_by_key(parameters, key, fragment):
    doc = {**V3, "landscape": "x", "parameters": parameters}
    with pytest.raises(SceneError) as refused:
        Scene.from_dict(doc)
    assert refused.value.key == key and fragment in refused.value.reason


def test_a_formula_uses_only_declared_parameters():
    with pytest.raises(SceneError, match="^landscape: unknown name 'b' at 3"):
        Scene.from_dict({**V3, "landscape": "a*b"})
    with pytest.raises(SceneError, match="is not a function"):
        Scene.from_dict({**V3, "landscape": "a(x)"})
    with pytest.raises(FormulaError, match="unknown name 'a'"):
        parse_formula("a*x")


def test_version_2_files_run_as_before_and_know_no_parameters():
    with pytest.raises(SceneError, match="^parameters: unknown key in a version-2 scene"):
        Scene.from_dict({**V3, "version": 2})
    with pytest.raises(SceneError, match="^omega: unknown key"):
        Scene.from_dict({**V3, "omega": {}})


def test_a_parameters_value_is_the_constant_written_in_the_formula():
    with_parameters = simulate(Scene.from_dict({**V3, "parameters": {"a": 0.5, "k": 1.0}}), t_end=1.0)
    hills = simulate(Scene.load(EXAMPLES_DIR / "hills.json"), t_end=1.0)   # 0.5*sin(x)*cos(y)
    assert with_parameters.status == hills.status == "ok"
    assert np.allclose(with_parameters.contact, hills.contact, rtol=0, atol=1e-12)
    assert np.allclose(with_parameters.energy, hills.energy, rtol=1e-12, atol=0)


def test_new_values_compile_nothing():
    scene = Scene.from_dict(V3)
    code = landscape_of(scene).compiled
    before = len(_COMPILED)
    ends = []
    for k in (0.5, 1.0, 2.0):
        varied = Scene.from_dict({**V3, "parameters": {"a": 0.5, "k": k}})
        assert landscape_of(varied).compiled is code
        ends.append(simulate(varied, t_end=0.5).contact[-1])
    assert len(_COMPILED) == before
    assert not np.allclose(ends[0], ends[2])


def test_a_sweep_over_a_parameter_gives_the_runs_one_by_one():
    scene = Scene.from_dict({**V3, "duration": 0.5})
    table = sweep(scene, {"parameters.k": [0.5, 1.0, 2.0], "start.x": [0.3, 0.4]}, workers=2)
    assert list(table.codes) == [KERNEL_STATUSES.index("ok")] * 6
    for row, (k, x) in enumerate(Grid.of({"parameters.k": [0.5, 1.0, 2.0], "start.x": [0.3, 0.4]}).values()):
        one = Scene.from_dict({**V3, "duration": 0.5, "parameters": {"a": 0.5, "k": k},
                               "start": {"x": x, "y": -0.2}})
        alone = sweep(one, {"start.x": [x]}, workers=1)
        assert np.array_equal(table.outcomes[row], alone.outcomes[0], equal_nan=True)


def test_a_sweep_refuses_a_parameter_the_scene_lacks():
    with pytest.raises(ValueError, match="the scene has no parameter 'b'"):
        sweep(Scene.from_dict(V3), {"parameters.b": [1.0]})
    with pytest.raises(ValueError, match="cannot vary 'parameters.sin'"):
        Grid.of({"parameters.sin": [1.0]})


def test_cli_sweeps_a_parameter_with_one_compile(tmp_path, capsys, monkeypatch):
    from rollball import landscape as landscape_module
    from rollball.cli import main

    path = tmp_path / "p.json"
    Scene.from_dict({**V3, "landscape": "a*sin(k*x)*cos(y) + 0.0123*x", "duration": 0.5}).save(path)
    compiles = []
    real = landscape_module._compile_or_refuse
    monkeypatch.setattr(landscape_module, "_compile_or_refuse", lambda source: compiles.append(source) or real(source))
    out = tmp_path / "out"
    assert main(["sweep", str(path), "--vary", "parameters.a=0:1:21", "--vary", "parameters.k=0.5:4:3",
                 "--workers", "2", "--out", str(out)]) == 0
    assert "63 of 63 runs" in capsys.readouterr().out and len(compiles) == 1
    rows = (out / "sweep.csv").read_text().splitlines()
    assert rows[0].startswith("parameters.a,parameters.k,status") and len(rows) == 64
    assert json.loads((out / "sweep.json").read_text())["scene"]["parameters"]["k"]["max"] == 4.0
    assert main(["sweep", str(path), "--vary", "parameters.b=0:1:2", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "no parameter 'b'" in err and "run/s" not in err   # refused before any progress bar


def test_a_formula_is_derived_once_however_it_is_asked_for():
    from rollball.landscape import landscape_for

    scene = Scene(landscape="0.0321*x*y")
    assert landscape_for("0.0321*x*y") is landscape_of(scene) is landscape_for("0.0321*x*y", [])
    with_a = Scene.from_dict({**V3, "landscape": "a*x", "parameters": {"a": 3}})
    assert landscape_for("a*x", ("a",)) is landscape_of(with_a)

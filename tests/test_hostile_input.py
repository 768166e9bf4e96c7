"""The hostile-input corpus (tests/hostile_corpus.py): every entry refused with a clear one-line
message, quickly, with nothing evaluated; the command line exits 2 with one line for each bad scene."""

import builtins
import importlib
import time

import pytest
import sympy as sp
from hostile_corpus import FORMULAS, SCENE_BYTES, SCENE_TEXTS

from rollball.cli import main
from rollball.formula import FormulaError, parse_formula
from rollball.scene import Scene, SceneError


def _cases(groups):
    return [pytest.param(*case, id=f"{group}-{i}") for group, cases in groups.items()
            for i, case in enumerate(cases)]


@pytest.fixture
def no_evaluators(monkeypatch):
    """eval, exec, sympify and parse_expr fail the test when given text (sympy's own internal
    sympify of sympy objects is harmless and allowed)."""
    def forbidden(original):
        def guard(*args, **kwargs):
            if any(isinstance(a, (str, bytes)) for a in args):
                raise AssertionError(f"text reached {original.__name__}: {args[0]!r}")
            return original(*args, **kwargs)
        return guard

    sympify_module = importlib.import_module("sympy.core.sympify")
    sympy_parser = importlib.import_module("sympy.parsing.sympy_parser")
    for module, name in [(builtins, "eval"), (builtins, "exec"), (sp, "sympify"),
                         (sympify_module, "sympify"), (sympy_parser, "parse_expr")]:
        monkeypatch.setattr(module, name, forbidden(getattr(module, name)))


@pytest.mark.parametrize("text, fragment", _cases(FORMULAS))
def test_hostile_formula_is_refused_quickly_with_nothing_evaluated(text, fragment, no_evaluators):
    start = time.perf_counter()
    with pytest.raises(FormulaError) as info:
        parse_formula(text)
    assert time.perf_counter() - start < 0.5
    message = str(info.value)
    assert fragment in message
    assert "\n" not in message and len(message) < 200


def test_injection_has_no_side_effect(tmp_path):
    target = tmp_path / "pwned"
    with pytest.raises(FormulaError):
        parse_formula(f'__import__("os").system("touch {target}")')
    assert not target.exists()


@pytest.mark.parametrize("text, key", _cases(SCENE_TEXTS))
def test_hostile_scene_text_is_refused_naming_the_key(text, key, no_evaluators):
    start = time.perf_counter()
    with pytest.raises(SceneError) as info:
        Scene.loads(text)
    assert time.perf_counter() - start < 0.5
    message = str(info.value)
    assert message.startswith(f"{key}:"), message
    assert "\n" not in message


@pytest.mark.parametrize("data, fragment", SCENE_BYTES)
def test_hostile_scene_file_is_refused(data, fragment, tmp_path):
    path = tmp_path / "scene.json"
    path.write_bytes(data)
    with pytest.raises(SceneError, match=fragment):
        Scene.load(path)


CLI_CASES = [(text.encode("utf-8"), key) for cases in SCENE_TEXTS.values() for text, key in cases] + SCENE_BYTES


@pytest.mark.parametrize("data, expected", CLI_CASES)
def test_command_line_refuses_hostile_scenes_in_one_line(data, expected, tmp_path, capsys):
    path = tmp_path / "scene.json"
    path.write_bytes(data)
    assert main(["simulate", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rollball: error: ")
    assert expected in lines[0]


def test_command_line_refuses_a_folder_as_scene(tmp_path, capsys):
    assert main(["simulate", str(tmp_path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "Is a directory" in lines[0]

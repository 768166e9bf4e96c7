"""The docs scripts that run for minutes check their outputs before they start."""

import importlib.util
import os
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parent.parent / "docs"


def _script(name):
    spec = importlib.util.spec_from_file_location(f"docs_{name}", DOCS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name, long_work", [("accuracy", "pairs"), ("sweep_liftoff", "sweep"),
                                             ("sweep_basins", "sweep")])
def test_an_output_that_cannot_be_written_is_refused_before_any_run(name, long_work, tmp_path, monkeypatch):
    module = _script(name)
    (tmp_path / "docs").mkdir()
    locked = tmp_path / "docs" / module.OUTPUTS[-1]
    locked.write_text("old")
    os.chmod(locked, 0o444)   # (refused by its mode bits, also for root)
    monkeypatch.setattr(module, "ROOT", tmp_path)

    def no_run(*args, **kwargs):
        raise AssertionError("the long work started")

    monkeypatch.setattr(module, long_work, no_run)
    with pytest.raises(OSError, match=module.OUTPUTS[-1]):
        module.main()
    assert locked.read_text() == "old"

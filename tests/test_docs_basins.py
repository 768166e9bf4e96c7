"""The basin map of the README and the manual is what docs/sweep_basins.py measured
(docs/sweep_basins.json): the example as shipped, the script's grid, the same table on Dask, and
the figures the manual quotes. When the script is run again and its figures move, this fails until
the manual says so."""

import importlib.util
import json
from pathlib import Path

import numpy as np

from rollball import Scene
from rollball.examples import scene_path

ROOT = Path(__file__).resolve().parent.parent
INFO = json.loads((ROOT / "docs" / "sweep_basins.json").read_text(encoding="utf-8"))
SUMMARY = INFO["summary"]
MANUAL = " ".join((ROOT / "docs" / "reference" / "sweeps.md").read_text(encoding="utf-8").split())
README = " ".join((ROOT / "README.md").read_text(encoding="utf-8").split())


def _script():
    spec = importlib.util.spec_from_file_location("docs_sweep_basins", ROOT / "docs" / "sweep_basins.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def number(n: int) -> str:
    """As the manual writes a count: 14 641."""
    return f"{n:,}".replace(",", " ")


def test_the_map_is_of_the_example_as_shipped_over_the_scripts_grid():
    assert INFO["scene"] == Scene.load(scene_path("wells")).to_dict()
    vary = _script().VARY
    assert [g["key"] for g in INFO["grid"]] == list(vary)
    for g, values in zip(INFO["grid"], vary.values()):
        assert np.array_equal(g["values"], values)
    command = "rollball sweep wells --vary start.x=-2.5:2.5:121 --vary start.y=-2.5:2.5:121 --color basin"
    assert command in MANUAL and command in README
    assert INFO["minima"] == SUMMARY["minima"] and len(INFO["minima"]) == 3


def test_dask_gave_the_same_table():
    assert SUMMARY["dask_same_table"] is True and SUMMARY["dask_workers"] >= 2


def test_the_manual_quotes_what_the_script_measured():
    s = SUMMARY
    ok, rested = s["status"]["ok"], s["rested"]
    quoted = [
        f"Of the {number(s['runs'])} runs, {number(rested)} come to rest",
        f"(the median after {s['rest_time']['median']:.2f} s, the last after {s['rest_time']['max']:.2f} s)",
        f"{number(s['basins']['1'])} in well 1, {number(s['basins']['2'])} in well 2, "
        f"{number(s['basins']['3'])} in well 3, none beside a saddle (basin 0)",
        "Every run ends `ok`" if ok == s["runs"] else f"{number(s['runs'] - ok)} end otherwise",
        f"Wall time **{s['seconds']:.1f} s** on the {s['workers']} local {s['local']} "
        f"({s['runs_per_second']:.0f} runs/s",
        f"on Dask **{s['dask_seconds']:.1f} s**, the same table to the last bit",
    ]
    for text in quoted:
        assert text in MANUAL, text
    assert ok == rested == s["runs"] and "0" not in s["basins"]
    assert sum(s["basins"].values()) == rested
    assert f"from each of {number(s['runs'])} points" in README

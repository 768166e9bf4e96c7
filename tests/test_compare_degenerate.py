"""A comparison too short to tell its runs apart (one step size, every error at the floor) is
drawn without a plotting library's warning reaching the user."""

import os
import subprocess
import sys
import warnings
from pathlib import Path

from rollball import Scene, compare, comparison_report
from rollball.examples import EXAMPLES_DIR


def test_a_panel_whose_points_share_one_x_or_one_y_gets_limits_of_its_own():
    fig = comparison_report.new_figure(6, 3)
    one, same, spread = fig.subplots(1, 3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        one.loglog([1e-10], [2e-14], marker="v")
        comparison_report.spread_limits(one, [1e-10], [2e-14])
        same.loglog([1e-5, 2e-5, 3e-5], [8e-15] * 3, marker="v")
        same.axhline(8e-15)
        comparison_report.spread_limits(same, [1e-5, 2e-5, 3e-5], [8e-15] * 3)
        spread.loglog([1e-3, 1e-2], [1e-6, 1e-4])
        comparison_report.spread_limits(spread, [1e-3, 1e-2], [1e-6, 1e-4])
        comparison_report.spread_limits(spread, [], [0.0, None])   # nothing drawn: nothing to do
        fig.canvas.draw()
    assert one.get_xlim() == (1e-10 / 10, 1e-10 * 10) and one.get_ylim() == (2e-14 / 10, 2e-14 * 10)
    assert same.get_ylim() == (8e-15 / 10, 8e-15 * 10) and same.get_xlim()[0] < 1e-5 < 3e-5 < same.get_xlim()[1]
    assert spread.get_autoscalex_on() and spread.get_autoscaley_on()   # matplotlib's own limits


def test_the_figure_of_a_comparison_of_one_step_draws_without_a_warning(tmp_path):
    cmp = compare(Scene.load(EXAMPLES_DIR / "hills.json"), t_end=1e-9, quick=True)
    assert len({r.dt for r in cmp.runs if r.spec.fixed_step}) == 1          # one step size: one x
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        data = comparison_report.figure(cmp)
        written = comparison_report.save(cmp, tmp_path)
    assert data.startswith(b"\x89PNG") and sorted(p.name for p in written) == sorted(comparison_report.FILES)


def test_the_compare_command_on_a_tiny_end_time_passes_no_library_warning_on(tmp_path):
    result = subprocess.run([sys.executable, "-m", "rollball", "compare", "hills", "--t-end", "1e-9", "--quick",
                             "--out", str(tmp_path)], capture_output=True, text=True, timeout=600, cwd=tmp_path,
                            env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])})
    assert result.returncode == 0, result.stderr
    assert not any(word in result.stderr for word in ("Warning", "xlims", "ylims")), result.stderr
    assert (tmp_path / "compare.png").read_bytes().startswith(b"\x89PNG")

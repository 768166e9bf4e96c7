"""``rollball check`` and ``rollball fit`` (docs/design.md §6, §10): the residuals and the fit's
report, the fitted scene and the residual plot written, bad input refused in one line before any
run, never a traceback."""

import numpy as np
import pytest

from rollball import Scene, Track
from rollball.cli import main
from rollball.examples import EXAMPLES_DIR

TRACK = "billiard_track.csv"   # an example track, found by its name like an example scene


def test_check_prints_the_residuals_and_says_the_model_does_not_explain_the_track(capsys):
    """The example track was made with μ = 0.25, v₀ = 2.2: the billiard scene (0.2, 2.0) is far off."""
    assert main(["check", "billiard", TRACK]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("billiard_track.csv: 69 positions (x, y)")
    assert "3 rows without a position skipped" in out[0]
    assert out[1].startswith("residual RMS ") and "largest" in out[1]
    assert out[2].startswith("the model does not explain the track")


def test_fit_reports_and_writes_the_fitted_scene_and_the_plot(tmp_path, capsys):
    out, plot = tmp_path / "fitted.json", tmp_path / "residuals.png"
    assert main(["fit", "billiard", TRACK, "--fit", "contact.friction,start.vx", "--out", str(out),
                 "--plot", str(plot)]) == 0
    text = capsys.readouterr().out
    assert "converged after" in text and "contact.friction = 0.25" in text and "start.vx         = 2.20" in text
    assert "correlations:" in text and "the model explains the track" in text
    fitted = Scene.load(out)
    assert fitted.contact.friction == pytest.approx(0.25, abs=0.004)
    assert fitted.start.vx == pytest.approx(2.2, abs=0.002)
    assert "Fitted to the track billiard_track.csv" in fitted.description
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_check_of_a_side_view_in_centimetres_with_a_title_line(tmp_path, capsys):
    """A Tracker export (title, tabs) of the billiard example seen from the side, in cm: x and z."""
    times = np.arange(1, 31) / 60
    exact = Track(times, ("x", "z"), np.zeros((30, 2)))
    from rollball.track_check import model_at, run_for  # the scene's own motion
    scene = Scene.load(EXAMPLES_DIR / "billiard.json")
    centre = model_at(run_for(scene, exact), scene, exact)
    rows = "\n".join(f"{t}\t{x * 100}\t{z * 100}" for t, (x, z) in zip(times, centre))
    path = tmp_path / "side.txt"
    path.write_text(f"mass A\nt\tx\ty\n{rows}\n")
    assert main(["check", "billiard", str(path), "--columns", "x=x,z=y", "--length-unit", "cm",
                 "--noise", "0.001"]) == 0
    out = capsys.readouterr().out
    assert "30 positions (x, z)" in out and "the model explains the track" in out


@pytest.mark.parametrize("args, words", [
    (["check", "billiard", "missing.csv"], "missing.csv: No such file"),
    (["check", "nowhere", TRACK], "no such scene file or example"),
    (["check", "billiard", TRACK, "--columns", "w=x"], "not t or a scene axis"),
    (["check", "billiard", TRACK, "--columns", "x=x,z=q"], "no column q (for z)"),
    (["fit", "billiard", TRACK, "--fit", "duration"], "cannot fit duration"),
    (["fit", "billiard", TRACK, "--fit", "contact.friction", "--bounds", "contact.friction=1:2"], "outside its bounds"),
    (["fit", "billiard", TRACK, "--fit", "contact.friction", "--bounds", "start.vx=1:2"], "not fitted"),
    (["fit", "billiard", TRACK, "--fit", "contact.friction", "--loss", "square"], "invalid choice"),
    (["fit", "billiard", TRACK], "required: --fit"),
    (["check", "billiard", TRACK, "--noise", "-1"], "greater than 0"),
])
def test_bad_input_is_refused_in_one_line(args, words, capsys):
    assert _status(args) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def _status(args) -> int:
    """The exit status: returned, or given to SystemExit by the argument parser."""
    try:
        return main(args)
    except SystemExit as e:
        return e.code


def test_a_bad_track_file_is_refused_naming_its_line_and_column(tmp_path, capsys):
    path = tmp_path / "bad.csv"
    path.write_text("t,x,y\n0,1,2\n0.1,1.5,x2\n")
    assert main(["check", "billiard", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.strip() == f"rollball: error: {path}: line 3: column y: x2 is not a number"


def test_outputs_are_checked_before_the_fit(tmp_path, capsys):
    """The input scene cannot be the output, nor can the two outputs be one file: refused at once."""
    scene = tmp_path / "scene.json"
    Scene.load(EXAMPLES_DIR / "billiard.json").save(scene)
    assert main(["fit", str(scene), TRACK, "--fit", "contact.friction", "--out", str(scene)]) == 2
    assert "cannot write" in capsys.readouterr().err
    same = str(tmp_path / "x")
    assert main(["fit", str(scene), TRACK, "--fit", "contact.friction", "--out", same, "--plot", same]) == 2
    assert "different files" in capsys.readouterr().err
    folder = tmp_path / "folder"
    folder.mkdir()
    assert main(["fit", str(scene), TRACK, "--fit", "contact.friction", "--plot", str(folder)]) == 2
    assert "cannot write" in capsys.readouterr().err


def test_the_fitted_scene_and_the_plot_are_replaced_together_or_not_at_all(tmp_path, capsys, monkeypatch):
    """The plot's rename fails: the old fitted scene stays too (the two are one set of outputs)."""
    import os

    out, plot = tmp_path / "fitted.json", tmp_path / "residuals.png"
    out.write_text("old scene")
    plot.write_bytes(b"old png")
    real = os.replace

    def failing(src, dst):
        if str(dst).endswith("residuals.png"):
            raise OSError(28, "No space left on device", str(dst))
        return real(src, dst)

    monkeypatch.setattr(os, "replace", failing)
    assert main(["fit", "billiard", TRACK, "--fit", "contact.friction", "--out", str(out), "--plot", str(plot)]) == 2
    monkeypatch.setattr(os, "replace", real)
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "none of fitted.json, residuals.png was replaced" in err
    assert out.read_text() == "old scene" and plot.read_bytes() == b"old png"
    kept = [p for p in tmp_path.iterdir() if p.name.startswith("fit-unsaved-")]
    assert len(kept) == 1 and sorted(os.listdir(kept[0])) == ["fitted.json", "residuals.png"]
    example = Scene.load(EXAMPLES_DIR / "billiard.json")
    assert Scene.load(kept[0] / "fitted.json").contact.friction != example.contact.friction


def test_the_outputs_must_share_a_folder(tmp_path, capsys):
    (tmp_path / "a").mkdir()
    assert main(["fit", "billiard", TRACK, "--fit", "contact.friction", "--out", str(tmp_path / "a" / "f.json"),
                 "--plot", str(tmp_path / "r.png")]) == 2
    assert "in one folder" in capsys.readouterr().err

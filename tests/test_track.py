"""Measured tracks read from files (docs/design.md §10): CSV and TSV, units in the header or by
option, Tracker's export with its title line, columns mapped to the scene's axes, lost frames
skipped and counted; a file that cannot be a track is refused in one line naming row and column."""

import math

import numpy as np
import pytest

from rollball import Track, TrackError
from rollball.track import parse_columns


def write(tmp_path, text, name="track.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_units_in_the_header_are_turned_into_metres_and_seconds(tmp_path):
    track = Track.load(write(tmp_path, "t [ms],x (cm),y (mm)\n0,1,2\n20,3,4\n40,5,6\n"))
    assert track.axes == ("x", "y") and track.skipped == 0
    assert track.t == pytest.approx([0.0, 0.02, 0.04])
    assert track.positions == pytest.approx(np.array([[0.01, 0.002], [0.03, 0.004], [0.05, 0.006]]))


def test_units_by_option_apply_where_the_header_names_none(tmp_path):
    path = write(tmp_path, "t,x,y,z\n0,1,2,3\n1,4,5,6\n")
    track = Track.load(path, length_unit="cm", time_unit="ms")
    assert track.axes == ("x", "y", "z")
    assert track.t == pytest.approx([0.0, 0.001])
    assert track.positions[1] == pytest.approx([0.04, 0.05, 0.06])


def test_trackers_export_a_title_line_tabs_and_lost_frames(tmp_path):
    """Tracker writes the track's name above the header; a frame where the ball was not found
    has empty cells. A side view's x and y are the scene's x and z."""
    text = "mass A\nt\tx\ty\n0.0\t0.10\t0.50\n0.033\t\t\n0.067\t0.20\t0.45\n0.1\tNaN\t0.4\n0.133\t0.3\t0.3\n"
    track = Track.load(write(tmp_path, text, "tracker.txt"), columns={"x": "x", "z": "y"})
    assert track.axes == ("x", "z") and track.skipped == 2
    assert track.t == pytest.approx([0.0, 0.067, 0.133])
    assert track.positions == pytest.approx(np.array([[0.1, 0.5], [0.2, 0.45], [0.3, 0.3]]))


def test_a_track_written_is_read_back_exactly(tmp_path):
    rng = np.random.default_rng(1)
    track = Track(np.arange(1, 11) / 60, ("y", "z"), rng.normal(size=(10, 2)))
    track.save(tmp_path / "out.csv", comments=("made here",))
    back = Track.load(tmp_path / "out.csv")
    assert back.axes == track.axes and back.skipped == 0
    assert np.array_equal(back.t, track.t) and np.array_equal(back.positions, track.positions)
    assert (tmp_path / "out.csv").read_text().startswith("# made here\n")


@pytest.mark.parametrize("text, options, words", [
    ("", {}, "empty"),
    ("x,y\n1,2\n3,4\n", {}, "no header"),
    ("t,x\n0,1\n1,2\n", {}, "two or three of x, y, z"),
    ("t,x,y\n0,1,2\n1,abc,3\n", {}, "line 3: column x: abc is not a number"),
    ("t,x,y\n0,1,2\n1,inf,3\n", {}, "line 3: column x: inf is not a finite number"),
    ("t,x,y\n0,1,2\n0,2,3\n", {}, "line 3: column t: the time 0 s does not follow 0 s"),
    ("t,x,y\n-1,1,2\n0,2,3\n", {}, "line 2: the time -1 s is before the scene's start"),
    ("t,x,y\n0,1,2\n,2,3\n", {}, "line 3: column t: no time"),
    ("t,x (in),y\n0,1,2\n1,2,3\n", {}, "unknown length unit in"),
    ("t,x (cm),y (cm)\n0,1,2\n1,2,3\n", {"length_unit": "mm"}, "is in cm, but the length unit given is mm"),
    ("t,x,y\n0,1,2\n", {}, "1 rows with a position"),
    ("t,x,y\n0,,\n1,,\n2,3,4\n", {}, "1 rows with a position (2 without)"),
    ("t,x,x\n0,1,2\n1,2,3\n", {}, "names column x twice"),
    ("t,x,y\n0,1,2\n1,2,3\n", {"columns": {"x": "u", "z": "y"}}, "no column u (for x)"),
    ("t,x,y\n0,1,2\n1,2,3\n", {"length_unit": "ft"}, "unknown length unit ft"),
])
def test_bad_files_are_refused_in_one_line(tmp_path, text, options, words):
    with pytest.raises(TrackError) as refused:
        Track.load(write(tmp_path, text), **options)
    message = str(refused.value)
    assert words in message and "\n" not in message and "track.csv" in message


def test_a_binary_file_and_a_folder_are_refused(tmp_path):
    with pytest.raises(TrackError, match="not a text file"):
        Track.load(_binary(tmp_path))
    with pytest.raises(OSError, match="folder"):
        Track.load(tmp_path)


def _binary(tmp_path):
    path = tmp_path / "video.mp4"
    path.write_bytes(b"\x00\x00\x00\x18ftypmp42\xff\xfe\x80")
    return path


@pytest.mark.parametrize("text, words", [("x", "AXIS=COLUMN"), ("w=x", "not t or a scene axis"),
                                          ("x=a,x=b", "given twice"), ("x=", "AXIS=COLUMN")])
def test_a_bad_column_mapping_is_refused(text, words):
    with pytest.raises(ValueError, match=words):
        parse_columns(text)


def test_the_noise_of_a_track_is_estimated_from_the_track_alone():
    """1 mm of white noise on a path that is smooth but for a bounce (its velocity jumps) and a lost
    frame (a gap in the times): the estimate is within 15 % of 1 mm for each of 20 seeds (its
    scatter is about 5 %), and within 5 % on average."""
    t = np.arange(1, 301) / 60
    t = np.delete(t, 150)                                          # a lost frame
    x = 2.0 * t + 0.3 * np.sin(3 * t)
    z = np.abs(np.sin(2.5 * t)) * 0.4                              # bounces: kinks at multiples of 1.26 s
    estimates = []
    for seed in range(20):
        rng = np.random.default_rng(seed)
        estimates.append(Track(t, ("x", "z"), np.column_stack([x, z]) + rng.normal(0, 1e-3, (len(t), 2))).noise())
        assert estimates[-1] == pytest.approx(1e-3, rel=0.15), seed
    assert np.mean(estimates) == pytest.approx(1e-3, rel=0.05)


def test_arrays_that_are_not_a_track_are_refused():
    t = np.arange(5.0)
    with pytest.raises(TrackError, match="increase"):
        Track(t[::-1], ("x", "y"), np.zeros((5, 2)))
    with pytest.raises(TrackError, match="different axes"):
        Track(t, ("x", "x"), np.zeros((5, 2)))
    with pytest.raises(TrackError, match="finite"):
        Track(t, ("x", "y"), np.full((5, 2), math.nan))
    with pytest.raises(TrackError, match="shape"):
        Track(t, ("x", "y"), np.zeros((4, 2)))

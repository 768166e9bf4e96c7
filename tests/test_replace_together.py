"""A set of files (a report, a sweep's outputs) is replaced together or not at all, and the
message says what happened; the checks before long work refuse what the write would."""

import os

import pytest

from rollball.files import STAGING_PREFIX, NotReplaced, check_outputs, replace_together

NEW = {"r.json": "new json", "r.md": "new md", "r.png": b"new png"}


@pytest.fixture
def old(tmp_path):
    replace_together(tmp_path, {"r.json": "old json", "r.md": "old md", "r.png": b"old png"})
    return tmp_path


def contents(folder):
    return {name: (folder / name).read_bytes() for name in ("r.json", "r.md", "r.png") if (folder / name).exists()}


OLD = {"r.json": b"old json", "r.md": b"old md", "r.png": b"old png"}


def no_staging_left(folder):
    return not [n for n in os.listdir(folder) if n.startswith(STAGING_PREFIX)]


def test_replaces_all_and_keeps_modes(old):
    os.chmod(old / "r.md", 0o640)
    written = replace_together(old, NEW)
    assert [p.name for p in written] == list(NEW)
    assert contents(old) == {k: v.encode() if isinstance(v, str) else v for k, v in NEW.items()}
    assert (os.stat(old / "r.md").st_mode & 0o777) == 0o640
    assert no_staging_left(old)


def test_a_read_only_member_replaces_none_and_keeps_the_new_set(old):
    os.chmod(old / "r.png", 0o444)
    with pytest.raises(NotReplaced) as caught:
        replace_together(old, NEW, kept_name="r-unsaved")
    assert contents(old) == OLD
    message = str(caught.value)
    assert "read-only" in message and "none of r.json, r.md, r.png was replaced" in message
    kept = caught.value.kept
    assert kept is not None and str(kept) in message and kept.parent == old
    assert sorted(os.listdir(kept)) == sorted(NEW)
    assert (kept / "r.json").read_text() == "new json"
    assert no_staging_left(old)


def test_a_fifo_member_replaces_none(old):
    os.unlink(old / "r.md")
    os.mkfifo(old / "r.md")
    with pytest.raises(NotReplaced, match="named pipe.*none of r.json, r.md, r.png was replaced"):
        replace_together(old, NEW)
    assert (old / "r.json").read_bytes() == b"old json" and (old / "r.png").read_bytes() == b"old png"
    assert no_staging_left(old)


def test_a_rename_failing_midway_puts_back_the_ones_before(old, monkeypatch):
    real = os.replace
    calls = []

    def failing(src, dst):
        calls.append(dst)
        if str(dst).endswith("r.png"):
            raise OSError(28, "No space left on device", str(dst))
        return real(src, dst)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(NotReplaced, match="No space left.*none of .* was replaced"):
        replace_together(old, NEW)
    monkeypatch.setattr(os, "replace", real)
    assert contents(old) == OLD
    assert no_staging_left(old)


def test_none_removes_an_old_member(old):
    replace_together(old, {"r.json": "a", "r.md": "b", "r.png": None})
    assert not (old / "r.png").exists() and (old / "r.json").read_text() == "a"


def test_check_outputs_refuses_before_the_work(old, tmp_path):
    os.chmod(old / "r.png", 0o444)
    with pytest.raises(OSError, match="read-only"):
        check_outputs(old, NEW)
    with pytest.raises(OSError, match="is a file, not a folder"):
        check_outputs(old / "r.json", NEW)
    fresh = tmp_path / "new" / "folder"
    assert [p.name for p in check_outputs(fresh, NEW)] == list(NEW)
    assert fresh.is_dir() and os.listdir(fresh) == []


def test_a_link_is_written_through_and_stays_a_link(old, tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "real.png").write_bytes(b"real old")
    os.unlink(old / "r.png")
    os.symlink(elsewhere / "real.png", old / "r.png")
    replace_together(old, NEW)
    assert os.path.islink(old / "r.png") and (elsewhere / "real.png").read_bytes() == b"new png"
    assert no_staging_left(old) and no_staging_left(elsewhere)

"""Saving a scene, exporting a CSV and writing bytes (the app's images) are atomic: a failing write leaves any
existing file intact, leaves no temporary file behind and raises an OSError naming the file."""

import errno
import functools
import os

import pytest
from conftest import make_scene

from rollball import simulate
from rollball.files import atomic_write_bytes
from rollball.scene import Scene


def scene_writer(path):
    Scene(landscape="x + y").save(path)


@functools.cache
def _run():   # (made before a test breaks os.replace or os.fsync: its formula's cache is written then)
    return simulate(make_scene("x*y"), t_end=0.01)


def csv_writer(path):
    _run().to_csv(path)


def bytes_writer(path):  # the app's image export
    atomic_write_bytes(path, b"\x89PNG\r\n\x1a\n")


WRITERS = [scene_writer, csv_writer, bytes_writer]


@pytest.fixture
def existing(tmp_path):
    _run()
    path = tmp_path / "out.txt"
    path.write_text("precious\n")
    return path


@pytest.mark.parametrize("write", WRITERS)
def test_failing_replace_keeps_the_old_file(write, existing, monkeypatch):
    def broken_replace(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError, match="No space left"):
        write(existing)
    assert existing.read_text() == "precious\n"
    assert os.listdir(existing.parent) == ["out.txt"]  # no temporary left behind


@pytest.mark.parametrize("write", WRITERS)
def test_failing_write_keeps_the_old_file(write, existing, monkeypatch):
    def broken_fsync(fd):
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(os, "fsync", broken_fsync)
    with pytest.raises(OSError, match="Input/output error"):
        write(existing)
    assert existing.read_text() == "precious\n"
    assert os.listdir(existing.parent) == ["out.txt"]


@pytest.mark.parametrize("write", WRITERS)
def test_missing_folder_is_named(write, tmp_path):
    target = tmp_path / "missing" / "out.txt"
    with pytest.raises(FileNotFoundError) as info:
        write(target)
    assert info.value.filename == str(target) and str(target) in str(info.value)


@pytest.mark.parametrize("write", WRITERS)
def test_read_only_folder_keeps_the_old_file(write, existing):
    # judged on the folder's mode bits, so root (who may write anywhere) is refused too
    os.chmod(existing.parent, 0o555)
    try:
        with pytest.raises(OSError, match="read-only folder") as info:
            write(existing)
        assert info.value.errno == errno.EACCES and str(existing) in str(info.value)
    finally:
        os.chmod(existing.parent, 0o755)
    assert existing.read_text() == "precious\n"


@pytest.mark.parametrize("write", WRITERS)
def test_success_replaces_the_file_and_keeps_its_mode(write, existing):
    os.chmod(existing, 0o600)
    write(existing)
    assert existing.read_bytes() != b"precious\n"
    assert existing.stat().st_mode & 0o777 == 0o600
    assert os.listdir(existing.parent) == ["out.txt"]

"""What is at a path decides what a write does: read-only and special files are refused, symbolic
links are written through, the scene being run is kept, new files honour the umask, and a write
interrupted by a signal leaves the old file and no temporary behind. Reading a scene refuses
anything that is not a regular file before it could block."""

import os
import signal
import stat
import subprocess
import sys
import textwrap
import time

import pytest
from conftest import make_scene

from rollball import simulate
from rollball.files import RefusedPath, atomic_write_bytes, open_regular, write_target
from rollball.scene import Scene


def scene_writer(path):
    Scene(landscape="x + y").save(path)


def csv_writer(path, keep=()):
    simulate(make_scene("x*y"), t_end=0.01).to_csv(path, keep=keep)


def bytes_writer(path, keep=()):  # the app's images, reports
    atomic_write_bytes(path, b"\x89PNG\r\n\x1a\n", keep=keep)


WRITERS = [scene_writer, csv_writer, bytes_writer]


def _special(kind, path):
    if kind == "folder":
        path.mkdir()
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "device":  # a copy of /dev/null's node: never the real one
        try:
            os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        except PermissionError:
            pytest.skip("making a device node needs root")
    return path


@pytest.mark.parametrize("write", WRITERS)
@pytest.mark.parametrize("mode", [0o444, 0o400, 0o555])
def test_read_only_files_are_refused_even_for_root(write, mode, tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("precious\n")
    os.chmod(target, mode)
    with pytest.raises(RefusedPath, match="read-only") as info:
        write(target)
    assert info.value.filename == str(target)
    assert target.read_text() == "precious\n" and stat.S_IMODE(target.stat().st_mode) == mode
    assert os.listdir(tmp_path) == ["out.txt"]


@pytest.mark.parametrize("write", WRITERS)
@pytest.mark.parametrize("kind, words", [("folder", "a folder"), ("fifo", "a named pipe"),
                                         ("device", "a character device")])
def test_special_files_are_refused_and_stay_what_they_are(write, kind, words, tmp_path):
    target = _special(kind, tmp_path / "special")
    before = target.lstat()
    with pytest.raises(RefusedPath, match=words):
        write(target)
    after = target.lstat()
    assert stat.S_IFMT(after.st_mode) == stat.S_IFMT(before.st_mode) and after.st_ino == before.st_ino
    assert os.listdir(tmp_path) == ["special"]


@pytest.mark.parametrize("write", WRITERS)
def test_symbolic_links_are_written_through(write, tmp_path):
    real = tmp_path / "data" / "real.txt"
    real.parent.mkdir()
    real.write_text("old\n")
    link = tmp_path / "link.txt"
    link.symlink_to(real)
    chain = tmp_path / "chain.txt"
    chain.symlink_to(link)
    write(chain)
    assert link.is_symlink() and chain.is_symlink() and os.readlink(chain) == str(link)
    assert real.read_bytes() != b"old\n" and chain.read_bytes() == real.read_bytes()
    assert sorted(os.listdir(tmp_path / "data")) == ["real.txt"]


def test_a_dangling_link_creates_the_file_it_names(tmp_path):
    link = tmp_path / "link.png"
    link.symlink_to(tmp_path / "new.png")
    bytes_writer(link)
    assert link.is_symlink() and (tmp_path / "new.png").read_bytes().startswith(b"\x89PNG")


@pytest.mark.parametrize("write", [csv_writer, bytes_writer])
def test_the_kept_file_is_refused_under_any_name(write, tmp_path):
    scene = tmp_path / "scene.json"
    Scene(landscape="x").save(scene)
    alias = tmp_path / "alias.json"
    alias.symlink_to(scene)
    text = scene.read_text()
    for name in (scene, alias, tmp_path / "." / "scene.json"):
        with pytest.raises(RefusedPath, match="scene being run"):
            write(name, keep=[scene])
    assert scene.read_text() == text


@pytest.mark.parametrize("write", WRITERS)
@pytest.mark.parametrize("umask, mode", [(0o077, 0o600), (0o022, 0o644), (0o002, 0o664)])
def test_new_files_honour_the_umask(write, umask, mode, tmp_path):
    old = os.umask(umask)
    try:
        write(tmp_path / "new.txt")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "new.txt").stat().st_mode) == mode


@pytest.mark.parametrize("write", WRITERS)
@pytest.mark.parametrize("mode", [0o640, 0o604, 0o755])
def test_existing_files_keep_mode_and_owner(write, mode, tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old\n")
    os.chmod(target, mode)
    owner = target.stat().st_uid, target.stat().st_gid
    write(target)
    info = target.stat()
    assert stat.S_IMODE(info.st_mode) == mode and (info.st_uid, info.st_gid) == owner


def test_an_empty_file_name_is_refused():
    with pytest.raises(RefusedPath, match="empty file name"):
        write_target("")


# A child that starts replacing a file, says so, then writes slowly until a signal arrives. It
# sets the dispositions the test relies on itself: started under nohup or trap '' INT HUP, it
# would inherit SIGHUP and SIGINT ignored (and Python installs no KeyboardInterrupt then).
SLOW_WRITER = textwrap.dedent("""
    import signal, sys, time
    from rollball.files import atomic_write

    for signum in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.default_int_handler)

    def write(stream):
        stream.write("new " * 1000)
        print("writing", flush=True)
        for _ in range(600):
            stream.write("more " * 1000)
            time.sleep(0.05)

    atomic_write(sys.argv[1], write)
""")


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP])
def test_a_signal_during_a_write_removes_the_temporary_and_keeps_the_old_file(signum, tmp_path):
    target = tmp_path / "export.csv"
    target.write_text("precious\n")
    child = subprocess.Popen([sys.executable, "-c", SLOW_WRITER, str(target)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "writing"
        assert any(name.endswith(".tmp") for name in os.listdir(tmp_path))  # it is mid-write
        child.send_signal(signum)
        child.wait(timeout=60)
    finally:
        child.kill()
        child.wait()
    assert child.returncode == -signum  # ended by the signal, as it would have without the clean-up
    assert target.read_text() == "precious\n"
    assert os.listdir(tmp_path) == ["export.csv"]


def test_reading_refuses_special_files_without_blocking(tmp_path):
    """In a child with a time limit: a FIFO opened the usual way would block forever."""
    fifo = _special("fifo", tmp_path / "scene.json")
    code = ("import sys\nfrom rollball.files import open_regular\n"
            "try:\n    open_regular(sys.argv[1])\nexcept OSError as e:\n    print(e.strerror)\n")
    started = time.perf_counter()
    result = subprocess.run([sys.executable, "-c", code, str(fifo)], capture_output=True, text=True, timeout=120)
    assert result.stdout.strip() == "is a named pipe (FIFO), not a regular file", result.stderr
    assert time.perf_counter() - started < 60


def test_reading_a_regular_file_through_a_link_works(tmp_path):
    real = tmp_path / "real.json"
    real.write_bytes(b"{}")
    (tmp_path / "link.json").symlink_to(real)
    with open_regular(tmp_path / "link.json") as stream:
        assert stream.read() == b"{}"
    with pytest.raises(RefusedPath, match="a folder"):
        open_regular(tmp_path)

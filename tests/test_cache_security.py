"""The cache folder holds code RollBall runs, so it is trusted only when it is ours alone, and
a file in it only when it is a regular file of ours of plausible size (docs/design.md §8).
Each attack runs in a process of its own, with a timeout far above the run's few seconds: a
FIFO read the old way would block it for ever."""

import json
import os
import shutil
import signal
import stat
import subprocess
import sys
import time

import pytest

from rollball import cache, landscape_code

NOBODY = 65534
FORMULA = "0.1*x*y + 0.05*x"
RUN = f"""
import json, sys
from rollball import Scene, machine_code, simulate
from rollball.cache import cache_dir
from rollball.landscape import Landscape
from rollball.scene import Start
traj = simulate(Scene(landscape={FORMULA!r}, start=Start(0.2, 0.1, 0.0, 0.0, 0.0), duration=0.05))
value = float(Landscape({FORMULA!r}).evaluate(2.0, 3.0)[0])
print(json.dumps({{"status": str(traj.status), "value": value, "folder": str(cache_dir()),
                  "source": machine_code.source}}))
"""
TIMEOUT = 300   # a run takes a few seconds (up to ~30 s on a loaded machine when it makes the kernel's code)


def run(folder, tmp_path, code=RUN, **env):
    """Run ``code`` with the cache folder ``folder`` and a temporary folder of its own (to see
    what it leaves there); its JSON line, its stderr, and what is left in its temporary folder."""
    scratch = tmp_path / "scratch"
    scratch.mkdir(exist_ok=True)
    environ = {**os.environ, "ROLLBALL_CACHE_DIR": str(folder), "TMPDIR": str(scratch), **env}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=TIMEOUT,
                            env=environ, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.strip().splitlines()[-1]), result.stderr, sorted(os.listdir(scratch))


@pytest.fixture(scope="module")
def warm(tmp_path_factory):
    """A cache folder holding the kernel's and the test formula's machine code."""
    folder = tmp_path_factory.mktemp("warm") / "cache"
    out, err, _ = run(folder, tmp_path_factory.mktemp("first"))
    assert out["status"] == "ok" and out["value"] == pytest.approx(0.7) and "warning" not in err
    return folder


@pytest.fixture
def ours(warm, tmp_path):
    folder = tmp_path / "cache"
    shutil.copytree(warm, folder)
    return folder


def only(folder, prefix):
    (path,) = folder.glob(f"{prefix}-*.o")
    return path


def warnings_in(err):
    return [line for line in err.splitlines() if line.startswith("rollball: warning:")]


# -- the folder ----------------------------------------------------------------------------

def test_a_folder_of_ours_is_used_and_holds_no_python_module_and_no_pickle(ours, tmp_path):
    out, err, left = run(ours, tmp_path)
    assert out["folder"] == str(ours) and out["value"] == pytest.approx(0.7) and warnings_in(err) == []
    assert stat.S_IMODE(ours.stat().st_mode) == 0o700 or not ours.stat().st_mode & 0o022
    names = [p.name for p in ours.rglob("*")]
    assert all(n.endswith(".o") and n.startswith(("kernel-", "landscape-")) for n in names), names
    assert left == []


def test_a_new_folder_is_made_private(tmp_path):
    folder = tmp_path / "new" / "cache"
    assert cache.unsafe(folder) is None
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700


@pytest.mark.parametrize("attack", ["mode 0777", "mode 0770", "owned by nobody", "link to nobody's"])
def test_a_folder_others_can_write_is_not_used_so_code_planted_there_does_not_run(attack, ours, tmp_path):
    # Planted: the machine code of another formula (4.25 everywhere) under the name the test
    # formula's code is kept under, and a numba index pickle that leaves a marker when loaded.
    # Were either read, the value would not be 0.7 or the marker would be there.
    planted = tmp_path / "planted"
    shutil.copytree(ours, planted)
    other = tmp_path / "other"
    shutil.copytree(ours, other)
    run(other, tmp_path, RUN.replace(repr(FORMULA), repr("4.25 + 0*x")))
    (code,) = set(other.glob("landscape-*.o")) - {other / only(ours, "landscape").name}
    shutil.copy(code, only(planted, "landscape"))
    marker = tmp_path / "marker"
    pickle_code = f"(S'x'\nI0\ntp0\n.cos\nsystem\n(S'touch {marker}'\ntR."   # (a pickle that runs a command)
    (planted / "__pycache__").mkdir()
    for name in ("rollball_landscape.landscape-4.py311.nbi", "landscape.landscape-4.py311.nbi"):
        (planted / "__pycache__" / name).write_text(pickle_code)
    folder = planted
    if attack == "mode 0777":
        planted.chmod(0o777)
    elif attack == "mode 0770":
        planted.chmod(0o770)
    else:
        for path in [planted, *planted.rglob("*")]:
            os.chown(path, NOBODY, NOBODY)
        if attack.startswith("link"):
            folder = tmp_path / "link"
            folder.symlink_to(planted)
    before = sorted(p.name for p in planted.rglob("*"))
    out, err, left = run(folder, tmp_path)
    assert out["value"] == pytest.approx(0.7) and out["status"] == "ok" and not marker.exists()
    assert out["folder"] != str(folder) and out["folder"] != str(planted)
    (line,) = warnings_in(err)
    assert "is not used" in line and ("write" in line or "another user" in line)
    assert sorted(p.name for p in planted.rglob("*")) == before      # nothing added or removed there
    assert left == []                                                   # the private folder is gone


def test_a_folder_inside_one_anyone_can_write_is_not_used(tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)   # (no sticky bit: anyone may rename our folder away and put theirs)
    assert "anyone can write" in cache.unsafe(shared / "cache")
    shared.chmod(0o1777)
    assert cache.unsafe(shared / "cache") is None


def test_no_private_folder_outlives_its_process_even_on_sigterm(tmp_path):
    shared = tmp_path / "open"
    shared.mkdir()
    shared.chmod(0o777)
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    code = ("import sys, time; from rollball.cache import cache_dir; print(cache_dir(), flush=True); "
            "time.sleep(60)")
    process = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, env={**os.environ, "ROLLBALL_CACHE_DIR": str(shared),
                                               "TMPDIR": str(scratch)})
    try:
        private = process.stdout.readline().strip()
        assert private.startswith(str(scratch / "rollball-"))
        assert stat.S_IMODE(os.stat(private).st_mode) == 0o700
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=60) == -signal.SIGTERM
    finally:
        process.kill()
        process.wait()
    assert os.listdir(scratch) == []
    assert process.stderr.read().count("rollball: warning:") == 1


# -- the files -----------------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["kernel", "landscape"])
def test_a_fifo_in_the_cache_folder_is_ignored_and_the_code_made_again(kind, ours, tmp_path):
    path = only(ours, kind)
    path.unlink()
    os.mkfifo(path)
    started = time.monotonic()
    out, err, _ = run(ours, tmp_path)
    # (a read of the fifo would block until ``run``'s TIMEOUT; making the code again took 30.4 s of
    # wall time on 2 cores running the suite and ``rollball bench`` together: half of TIMEOUT is 5×)
    assert out["value"] == pytest.approx(0.7) and out["status"] == "ok" and time.monotonic() - started < TIMEOUT / 2
    (line,) = warnings_in(err)
    assert path.name in line and "not a regular file" in line
    assert stat.S_ISREG(path.lstat().st_mode)   # made again, in its place
    _, err, _ = run(ours, tmp_path)
    assert warnings_in(err) == []


@pytest.mark.parametrize("kind", ["kernel", "landscape"])
def test_a_huge_file_in_the_cache_folder_is_not_read(kind, ours, tmp_path):
    path = only(ours, kind)
    with open(path, "r+b") as f:
        f.truncate(6 << 30)   # 6 GB, sparse: reading it would need the memory
    out, err, _ = run(ours, tmp_path)
    assert out["value"] == pytest.approx(0.7) and "MemoryError" not in err
    (line,) = warnings_in(err)
    assert path.name in line and "6,442,450,944 bytes" in line
    assert path.stat().st_size < 64 << 20


@pytest.mark.parametrize("kind", ["kernel", "landscape"])
def test_a_file_of_another_user_or_a_link_in_the_cache_folder_is_not_read(kind, ours, tmp_path):
    path = only(ours, kind)
    os.chown(path, NOBODY, NOBODY)
    out, err, _ = run(ours, tmp_path)
    assert out["value"] == pytest.approx(0.7) and "another user" in warnings_in(err)[0]
    assert path.stat().st_uid == os.geteuid()
    target = tmp_path / "elsewhere.o"
    shutil.move(path, target)
    path.symlink_to(target)
    out, err, _ = run(ours, tmp_path)
    assert out["value"] == pytest.approx(0.7) and "symbolic link" in warnings_in(err)[0]
    assert not path.is_symlink()


def test_read_refuses_what_is_not_a_plain_file_of_ours(tmp_path, capsys):
    plain = tmp_path / "plain"
    plain.write_bytes(b"12345")
    assert cache.read(plain, 5, "test file") == b"12345"
    assert cache.read(plain, 4, "test file") is None
    assert cache.read(tmp_path / "missing", 5, "test file") is None
    os.mkfifo(tmp_path / "fifo")
    assert cache.read(tmp_path / "fifo", 5, "test file") is None
    (tmp_path / "link").symlink_to(plain)
    assert cache.read(tmp_path / "link", 5, "test file") is None
    assert cache.read(tmp_path, 5, "test file") is None
    os.chown(plain, NOBODY, NOBODY)
    assert cache.read(plain, 5, "test file") is None
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 5 and all(line.startswith("rollball: warning: ignored the cached test file") for line in lines)
    assert cache.write(tmp_path / "fifo", b"code") is None and (tmp_path / "fifo").read_bytes() == b"code"


def test_landscape_code_checks_its_entry_whole(tmp_path):
    assert landscape_code._unpack(b"short") is None
    assert landscape_code._unpack(None) is None
    data = b'{"calls": ["sin"]}\ncode'
    import hashlib

    entry = hashlib.sha256(data).digest() + data
    assert landscape_code._unpack(entry) == (["sin"], b"code")
    assert landscape_code._unpack(entry[:-1] + b"x") is None


@pytest.mark.skipif(shutil.which("gcc") is None, reason="the benchmark's C step needs gcc")
def test_the_benchmarks_c_step_leaves_no_folder_behind(tmp_path):
    code = "from rollball.bench.cstep import CStep; print(CStep.build().executable.is_file())"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=TIMEOUT,
                            env={**os.environ, "TMPDIR": str(tmp_path)})
    assert result.stdout.strip() == "True", result.stderr
    assert os.listdir(tmp_path) == []


def test_numbas_cache_folder_is_ours_alone_too(tmp_path):
    # numba keeps the kernel it compiles (where the shipped code does not fit) with a pickled
    # index in $NUMBA_CACHE_DIR: one that others can write is replaced by one in our folder
    code = "import rollball; from numba.core import config; print(config.CACHE_DIR)"
    ours = tmp_path / "ours"
    for mode, used in ((0o777, ours / "numba"), (0o700, tmp_path / "numba")):
        (tmp_path / "numba").mkdir(exist_ok=True)
        (tmp_path / "numba").chmod(mode)
        result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=TIMEOUT,
                                env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
                                     "ROLLBALL_CACHE_DIR": str(ours)})
        assert result.returncode == 0, result.stderr
        assert result.stdout.strip() == str(used)
        assert len(warnings_in(result.stderr)) == (1 if mode == 0o777 else 0)


# -- every folder on the way ----------------------------------------------------------------

def parent(tmp_path, mode=0o755, owner=None):
    """A folder holding a cache folder of ours (mode 0700): the parent's ``mode`` and owner."""
    above = tmp_path / "above"
    above.mkdir()
    (above / "cache").mkdir(mode=0o700)
    above.chmod(mode)
    if owner is not None:
        os.chown(above, owner, owner)
    return above


@pytest.mark.parametrize("mode, owner, why", [
    (0o755, NOBODY, "which another user owns"),          # another user's home folder, say
    (0o775, None, "which its group can write to"),
    (0o777, None, "which anyone can write to"),
    (0o770, NOBODY, "which another user owns"),
])
def test_a_folder_inside_one_another_user_may_change_is_not_used(tmp_path, mode, owner, why):
    # whoever may rename what is in the parent may put a folder of theirs (or a link) in place
    # of ours after the check: the folder is ours, but it is not trusted
    above = parent(tmp_path, mode, owner)
    reason = cache.unsafe(above / "cache")
    assert reason == f"inside {above}, which {why.split('which ')[1]}"
    assert cache.unsafe(above / "new", make=True) is not None and not (above / "new").exists()   # nothing made there


@pytest.mark.parametrize("mode", [0o1777, 0o1770, 0o1775])
def test_a_folder_inside_a_sticky_one_is_used(tmp_path, mode):
    # as /tmp: others may write there, but not rename or remove what is ours
    above = parent(tmp_path, mode)
    assert cache.trusted(above / "cache") == (str(above / "cache"), None)
    assert cache.unsafe(above / "new") is None and stat.S_IMODE((above / "new").stat().st_mode) == 0o700


def test_each_folder_up_to_the_root_is_checked(tmp_path):
    above = parent(tmp_path)
    (above / "cache" / "deeper" / "still").mkdir(parents=True, mode=0o700)
    assert cache.unsafe(above / "cache" / "deeper" / "still") is None
    tmp_path.chmod(0o777)
    try:
        assert cache.unsafe(above / "cache" / "deeper" / "still") == f"inside {tmp_path}, which anyone can write to"
    finally:
        tmp_path.chmod(0o700)


def test_a_symbolic_link_on_the_way_is_followed_with_care(tmp_path):
    above = parent(tmp_path)
    link = tmp_path / "link"
    link.symlink_to(above)
    assert cache.trusted(link / "cache") == (str(above / "cache"), None)   # ours, to a safe place: its real path
    relative = tmp_path / "relative"
    relative.symlink_to("above/./../above")
    assert cache.trusted(relative / "cache") == (str(above / "cache"), None)
    # a link another user owns may be replaced by them (in a sticky folder, say)
    os.chown(link, NOBODY, NOBODY, follow_symlinks=False)
    assert cache.unsafe(link / "cache") == f"{link} is a symbolic link owned by another user"
    # a link of ours to a place another user may change: the place is checked
    shared = tmp_path / "shared"
    shared.mkdir()
    (shared / "cache").mkdir(mode=0o700)
    shared.chmod(0o775)
    ours = tmp_path / "ours"
    ours.symlink_to(shared / "cache")
    assert cache.unsafe(ours) == f"inside {shared}, which its group can write to"
    loop = tmp_path / "loop"
    loop.symlink_to(loop)
    assert "too many symbolic links" in cache.unsafe(loop / "cache")


def test_a_cache_folder_in_another_users_home_is_not_used_and_one_line_says_why(ours, tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    folder = home / "cache"
    shutil.move(ours, folder)
    os.chown(home, NOBODY, NOBODY)     # nobody's, who may rename our folder and put theirs
    out, err, left = run(folder, tmp_path)
    assert out["value"] == pytest.approx(0.7) and out["status"] == "ok"
    assert out["folder"] != str(folder)
    (line,) = warnings_in(err)
    assert f"the cache folder {folder} is not used (inside {home}, which another user owns)" in line
    assert left == []


def test_numbas_cache_folder_inside_a_group_writable_one_is_not_used(tmp_path):
    above = parent(tmp_path, 0o775)
    code = "import rollball; from numba.core import config; print(config.CACHE_DIR)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=TIMEOUT,
                            env={**os.environ, "NUMBA_CACHE_DIR": str(above / "cache"),
                                 "ROLLBALL_CACHE_DIR": str(tmp_path / "ours")})
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == str(tmp_path / "ours" / "numba")
    (line,) = warnings_in(result.stderr)
    assert "which its group can write to" in line


def test_where_no_folder_may_be_trusted_nothing_is_kept_on_disk(tmp_path):
    # the cache folder inside a group-writable one, and so is the temporary folder: the code is
    # compiled in memory, and nothing is read from or written to either
    above = parent(tmp_path, 0o775)
    temporary = tmp_path / "temporary"
    temporary.mkdir(mode=0o777)
    temporary.chmod(0o777)
    out, err, _ = run(above / "cache", tmp_path, TMPDIR=str(temporary))
    assert out["value"] == pytest.approx(0.7) and out["status"] == "ok"
    (line,) = warnings_in(err)
    assert f"the cache folder {above / 'cache'} is not used (inside {above}, which its group can write to)" in line
    assert "which anyone can write to" in line and line.endswith("compiled code is kept in memory only")
    assert list((above / "cache").iterdir()) == [] and os.listdir(temporary) == []

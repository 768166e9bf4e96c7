"""Where RollBall keeps compiled code between runs (the kernel's machine code, machine_code.py,
and the landscapes' machine code, landscape.py), and how it reads it back.

What is kept there is code that runs inside RollBall, so the folder and every file read from it
are checked (docs/design.md §8):

- The folder ($ROLLBALL_CACHE_DIR, else $XDG_CACHE_HOME/rollball, else ~/.cache/rollball; made
  with mode 0700 when missing) is used only when it is a folder owned by this user that neither
  its group nor others may write, and every folder on the way to it from the root (symbolic
  links followed one at a time, each of them this user's or root's) is this user's or root's
  and writable by no one else, unless sticky, as /tmp (``trusted``). Otherwise one warning line
  on stderr naming the folder and why, and a private folder (``tempfile.mkdtemp``, mode 0700)
  for this process only, removed when it ends (at exit, and on SIGTERM where no other handler
  is installed); where even that one fails the same check, nothing is kept on disk: code is
  compiled in memory.
- A file is read only when, opened without following a link and without blocking, it is a
  regular file owned by this user and at most ``limit`` bytes long (``read``). Anything else
  is ignored with one warning line (and rebuilt by the caller); ``write`` replaces it.
"""

from __future__ import annotations

import atexit
import errno
import os
import shutil
import signal
import stat
import sys
import tempfile
import threading
from pathlib import Path

from .files import atomic_write_bytes
from .text import shown

_CACHE_DIR: Path | None = None
_IN_MEMORY = False   # no folder may be trusted: nothing is read from or written to disk
_LOCK = threading.Lock()
# Ownership and mode bits say who may write only on POSIX systems (Windows has ACLs instead, and
# no geteuid): there the checks below that need them are skipped.
_POSIX = hasattr(os, "geteuid")


def configured() -> str:
    """The cache folder asked for, before any check."""
    return os.environ.get("ROLLBALL_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "rollball")


def cache_dir() -> Path:
    """The cache folder this process uses: the configured one where it is safe (see above), else
    a private folder removed when the process ends. Decided once per process."""
    global _CACHE_DIR, _IN_MEMORY
    if _CACHE_DIR is None:
        with _LOCK:
            if _CACHE_DIR is None:
                base = configured()
                real, reason = trusted(base)
                if reason is None:
                    _CACHE_DIR = Path(real)
                else:
                    _CACHE_DIR = _private_folder()
                    private, problem = trusted(_CACHE_DIR, make=False)
                    if problem is None:
                        _CACHE_DIR = Path(private)
                        warn(f"the cache folder {shown(base)} is not used ({reason}); compiled code is kept "
                             f"in {shown(str(_CACHE_DIR))} until this process ends")
                    else:
                        _IN_MEMORY = True
                        warn(f"the cache folder {shown(base)} is not used ({reason}), nor a temporary one "
                             f"({shown(str(_CACHE_DIR))}: {problem}); compiled code is kept in memory only")
    return _CACHE_DIR


def unsafe(folder: str | os.PathLike, make: bool = True) -> str | None:
    """Why ``folder`` must not hold code RollBall runs, or None when it may (made, mode 0700,
    when missing and ``make``). See ``trusted``."""
    return trusted(folder, make)[1]


def trusted(folder: str | os.PathLike, make: bool = True) -> tuple[str | None, str | None]:
    """(the real path of ``folder``, None) when it may hold code RollBall runs, else (None, why).

    Every folder from the root to it must be owned by this user or root and writable by no one
    else (its group and others may not write to it), except a sticky folder such as /tmp, where
    others cannot rename or remove what is not theirs (as ssh's StrictModes); the folder itself
    must be this user's, writable by no one else. The path is followed one name at a time, with
    ``os.lstat``: a symbolic link on the way must be this user's or root's (only they may then
    replace it), and the folders it leads to are checked in turn. Otherwise whoever may write to
    one of them could put a folder of theirs (or a link to one) in its place after the check.
    Missing folders are made (mode 0700) when ``make``, each inside one already checked."""
    path = os.fsdecode(os.fspath(folder))
    if not _POSIX:
        try:
            if make:
                os.makedirs(path, mode=0o700, exist_ok=True)
            real = os.path.realpath(path)
            if not os.path.isdir(real):
                return None, "not a folder"
        except OSError as error:
            return None, error.strerror or str(error)
        return (real, None) if os.access(real, os.W_OK) else (None, "cannot be written")
    if not path:
        return None, "no folder named"
    try:
        if not os.path.isabs(path):
            path = os.path.join(os.getcwd(), path)
        me = os.geteuid()
        pending = [name for name in path.split(os.sep) if name not in ("", ".")]
        current, links = os.sep, 0
        problem = _shared(current, os.lstat(current), me)
        if problem:
            return None, problem
        while pending:
            name = pending.pop(0)
            if name == "..":
                current = os.path.dirname(current)   # a folder already checked
                continue
            candidate = os.path.join(current, name)
            try:
                info = os.lstat(candidate)
            except FileNotFoundError:
                if not make:
                    raise
                try:
                    os.mkdir(candidate, 0o700)
                except FileExistsError:
                    pass
                info = os.lstat(candidate)
            if stat.S_ISLNK(info.st_mode):
                links += 1
                if links > 40:
                    return None, f"{shown(candidate)}: too many symbolic links"
                if info.st_uid not in (me, 0):
                    return None, f"{shown(candidate)} is a symbolic link owned by another user"
                target = os.readlink(candidate)
                if os.path.isabs(target):
                    current = os.sep
                pending[:0] = [part for part in target.split(os.sep) if part not in ("", ".")]
                continue
            if not stat.S_ISDIR(info.st_mode):
                return None, ("not a folder" if not pending else f"{shown(candidate)} is not a folder")
            if pending:
                problem = _shared(candidate, info, me)
                if problem:
                    return None, problem
            current = candidate
        info = os.lstat(current)
    except OSError as error:
        return None, error.strerror or str(error)
    if info.st_uid != me:
        return None, "owned by another user"
    if info.st_mode & 0o022:
        return None, (f"mode {stat.S_IMODE(info.st_mode):04o}: its group or others can write to it; "
                      f"'chmod go-w' makes it usable")
    if not os.access(current, os.W_OK | os.X_OK):
        return None, "cannot be written"
    return current, None


def _shared(path: str, info: os.stat_result, me: int) -> str | None:
    """Why someone else could replace what is inside the folder ``path`` (``info``: its
    lstat), or None: it is this user's or root's, and neither its group nor others may write
    to it unless it is sticky."""
    if info.st_uid not in (me, 0):
        return f"inside {shown(path)}, which another user owns"
    if info.st_mode & stat.S_ISVTX:
        return None
    if info.st_mode & 0o002:
        return f"inside {shown(path)}, which anyone can write to"
    if info.st_mode & 0o020:
        return f"inside {shown(path)}, which its group can write to"
    return None


def guard_numba_cache() -> None:
    """numba keeps what it compiles with ``cache=True`` (the kernel, where the shipped code does not
    fit) in $NUMBA_CACHE_DIR when that is set, with an index that is a pickle: a folder others can
    write would let them run code here. Such a folder is replaced, for this process and those it
    starts, by one inside RollBall's checked cache folder (one warning line)."""
    folder = os.environ.get("NUMBA_CACHE_DIR")
    if not folder:
        return
    reason = unsafe(folder)
    if reason is None:
        return
    instead = cache_dir() / "numba"
    os.environ["NUMBA_CACHE_DIR"] = str(instead)
    config = sys.modules.get("numba.core.config")
    if config is not None:
        config.reload_config()
    warn(f"numba's cache folder {shown(folder)} is not used ({reason}); {shown(str(instead))} is used instead")


def warn(message: str) -> None:
    """One warning line on stderr."""
    try:
        print(f"rollball: warning: {message}", file=sys.stderr, flush=True)
    except (OSError, ValueError):   # no stderr (closed, or a GUI process without one)
        pass


def read(path: str | os.PathLike, limit: int, what: str) -> bytes | None:
    """The bytes of the cached file ``path``, or None when it is missing or must not be trusted:
    not a regular file (a FIFO, a device, a folder, a symbolic link), owned by someone else, or
    longer than ``limit`` bytes (``what`` names it in the one-line warning). None too when no
    folder may be trusted (``cache_dir``)."""
    if _IN_MEMORY:
        return None
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        return None
    except OSError as error:
        problem = "a symbolic link" if error.errno == errno.ELOOP else (error.strerror or str(error))
        warn(f"ignored the cached {what} {shown(str(path))} ({problem}); it is made again")
        return None
    try:
        info = os.fstat(fd)
        problem = None
        if not stat.S_ISREG(info.st_mode):
            problem = "not a regular file"
        elif _POSIX and info.st_uid != os.geteuid():
            problem = "owned by another user"
        elif info.st_size > limit:
            problem = f"{info.st_size:,} bytes, more than the {limit:,} it can be"
        if problem is None:
            os.set_blocking(fd, True)
            chunks, size = [], 0
            while size <= limit:
                chunk = os.read(fd, min(1 << 20, limit + 1 - size))
                if not chunk:
                    return b"".join(chunks)
                chunks.append(chunk)
                size += len(chunk)
            problem = f"grew beyond {limit:,} bytes"
    except OSError as error:
        problem = error.strerror or str(error)
    finally:
        os.close(fd)
    warn(f"ignored the cached {what} {shown(str(path))} ({problem}); it is made again")
    return None


def write(path: str | os.PathLike, data: bytes) -> str | None:
    """Keep ``data`` at ``path`` for later processes, replacing whatever is there (a file that
    ``read`` refused included). None when written, else why not (that costs only time).
    Not forced to disk (no fsync, 5-20 ms on a busy disk): every entry begins with the SHA-256
    of the rest, checked by its reader, so one torn by a crash is rebuilt, never used.
    Nothing is written when no folder may be trusted (``cache_dir``)."""
    if _IN_MEMORY:
        return None
    try:
        info = os.lstat(path)
        if not stat.S_ISREG(info.st_mode) or _POSIX and info.st_uid != os.geteuid():
            os.unlink(path)
    except FileNotFoundError:
        pass
    except OSError as error:
        return error.strerror or str(error)
    try:
        atomic_write_bytes(path, data, durable=False)
    except OSError as error:
        return error.strerror or str(error)
    return None


def unwritable(path: str | os.PathLike) -> str | None:
    """Why ``write`` could not keep a file at ``path``, known before anything is made, or None:
    a read-only folder, or a read-only file of ours where it would replace one (the mode bits
    decide, as for every file RollBall writes: root too respects them; rollball.files)."""
    if _IN_MEMORY:
        return None
    folder = os.path.dirname(os.fspath(path)) or "."
    try:
        mode = os.stat(folder).st_mode
        if not mode & 0o222 or not os.access(folder, os.W_OK | os.X_OK):
            return "its folder is read-only"
        try:
            info = os.lstat(path)
        except FileNotFoundError:
            return None
    except OSError as error:
        return error.strerror or str(error)
    replaced = stat.S_ISREG(info.st_mode) and not (_POSIX and info.st_uid != os.geteuid())
    if replaced and (not info.st_mode & 0o222 or not os.access(path, os.W_OK)):
        return "a read-only file"
    return None


# -- the private folder ------------------------------------------------------------------

def _private_folder() -> Path:
    folder = tempfile.mkdtemp(prefix="rollball-")   # mode 0700, made for this process
    atexit.register(_remove, folder)
    _remove_on_sigterm(folder)
    return Path(folder)


def _remove(folder: str) -> None:
    shutil.rmtree(folder, ignore_errors=True)


def _remove_on_sigterm(folder: str) -> None:
    """SIGTERM ends a process without running atexit: where nobody handles it (the default
    action), remove the folder first, then end as the signal would have. A handler installed
    later replaces this one; the folder is then removed at exit if the process exits."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "SIGTERM"):
        return
    try:
        if signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
            return
    except ValueError:
        return

    def terminate(signum, frame):
        _remove(folder)
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)

    try:
        signal.signal(signal.SIGTERM, terminate)
    except ValueError:
        pass

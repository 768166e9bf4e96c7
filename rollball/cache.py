"""Where RollBall keeps compiled code between runs (the kernel's machine code, machine_code.py,
and the landscapes' machine code, landscape.py), and how it reads it back.

What is kept there is code that runs inside RollBall, so the folder and every file read from it
are checked (docs/design.md §8):

- The folder ($ROLLBALL_CACHE_DIR, else $XDG_CACHE_HOME/rollball, else ~/.cache/rollball; made
  with mode 0700 when missing) is used only when, with symbolic links resolved, it is a folder
  owned by this user that neither its group nor others may write, inside folders that others
  may not write either (unless sticky, as /tmp). Otherwise one warning line on stderr, and a
  private folder (``tempfile.mkdtemp``, mode 0700) for this process only, removed when it ends
  (at exit, and on SIGTERM where no other handler is installed).
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
    global _CACHE_DIR
    if _CACHE_DIR is None:
        with _LOCK:
            if _CACHE_DIR is None:
                base = configured()
                reason = unsafe(base)
                if reason is None:
                    _CACHE_DIR = Path(os.path.realpath(base))
                else:
                    _CACHE_DIR = _private_folder()
                    warn(f"the cache folder {shown(base)} is not used ({reason}); compiled code is kept "
                         f"in {shown(str(_CACHE_DIR))} until this process ends")
    return _CACHE_DIR


def unsafe(folder: str | os.PathLike, make: bool = True) -> str | None:
    """Why ``folder`` must not hold code RollBall runs, or None when it may (made, mode 0700,
    when missing and ``make``)."""
    try:
        if make:
            os.makedirs(folder, mode=0o700, exist_ok=True)
        real = os.path.realpath(folder)
        info = os.lstat(real)
    except OSError as error:
        return error.strerror or str(error)
    if not stat.S_ISDIR(info.st_mode):
        return "not a folder"
    if not _POSIX:
        return None if os.access(real, os.W_OK) else "cannot be written"
    if info.st_uid != os.geteuid():
        return "owned by another user"
    if info.st_mode & 0o022:
        return (f"mode {stat.S_IMODE(info.st_mode):04o}: its group or others can write to it; "
                f"'chmod go-w' makes it usable")
    above = real
    while os.path.dirname(above) != above:
        above = os.path.dirname(above)
        try:
            mode = os.stat(above).st_mode
        except OSError as error:
            return error.strerror or str(error)
        if mode & 0o002 and not mode & stat.S_ISVTX:
            return f"inside {shown(above)}, which anyone can write to"
    if not os.access(real, os.W_OK | os.X_OK):
        return "cannot be written"
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
    longer than ``limit`` bytes (``what`` names it in the one-line warning)."""
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
    of the rest, checked by its reader, so one torn by a crash is rebuilt, never used."""
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

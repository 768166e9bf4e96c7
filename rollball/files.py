"""Reading and writing the user's files safely: the one write path of the program.

Every file RollBall writes (scenes, CSV exports, images, reports) goes through
``atomic_write``: a temporary file beside the target, then one rename. What is at the
path decides what happens:

- a missing file is created with the permissions the umask allows;
- an existing regular file is replaced whole or not at all, keeping its permissions
  (and its owner and group where the system allows it);
- a symbolic link is written *through*: the file it names is replaced, the link stays;
- a read-only file or a file in a read-only folder (no write permission bit set, whoever
  runs the program; root too), a folder, a named pipe, a device or a socket is refused,
  and nothing is written;
- a path given in ``keep`` (the scene being run) is refused too.

A refusal or a failing write (missing folder, full disk) raises ``OSError`` naming the
path and leaves any existing file untouched. Interrupting the program (Ctrl-C, SIGTERM,
SIGHUP) during a write removes the temporary file; the old file stays intact.

``open_regular`` opens a file for reading only if it is a regular file: a named pipe
would block the program forever, a device never end.
"""

from __future__ import annotations

import errno
import os
import signal
import stat
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Callable, Iterable

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe (FIFO)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))
# Signals whose default action ends the program: a write they interrupt removes its temporary file.
_TERMINATING = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


class RefusedPath(OSError):
    """A path RollBall will not read or write; ``strerror`` says why, ``filename`` names it."""


def _kind(mode: int) -> str | None:
    """What a non-regular file is, in words (None for a regular file)."""
    return next((words for test, words in _KINDS if test(mode)), None if stat.S_ISREG(mode) else "not a regular file")


def _refuse(path, reason: str, code: int = errno.EPERM) -> RefusedPath:
    return RefusedPath(code, reason, str(path))


def write_target(path: str | os.PathLike, keep: Iterable[str | os.PathLike] = ()) -> Path:
    """The file a write to ``path`` would replace or create (symbolic links followed), after
    checking it may be written; raises ``RefusedPath`` (an ``OSError``) if not.

    Call it before long work whose result goes to ``path``, so a refusal comes first."""
    if os.fspath(path) == "":
        raise _refuse(path, "empty file name", errno.ENOENT)
    target = Path(os.path.realpath(path))
    try:
        folder = target.parent.stat().st_mode
    except OSError:  # a missing folder: the write fails naming the file
        folder = None
    if folder is not None and stat.S_ISDIR(folder) and not folder & 0o222:
        raise _refuse(path, "is in a read-only folder; nothing was written", errno.EACCES)
    try:
        info = target.stat()
    except FileNotFoundError:
        return target
    except NotADirectoryError:  # a part of the path is a file: the write fails naming it
        return target
    kind = _kind(info.st_mode)
    if kind is not None:
        raise _refuse(path, f"is {kind}, not a regular file; nothing was written",
                      errno.EISDIR if stat.S_ISDIR(info.st_mode) else errno.EPERM)
    if not info.st_mode & 0o222 or not os.access(target, os.W_OK):
        raise _refuse(path, "is read-only; nothing was written", errno.EACCES)
    for other in keep:
        try:
            same = os.path.samefile(target, other)
        except OSError:
            same = False
        if same:
            raise _refuse(path, "is the scene being run; nothing was written")
    return target


def _umask() -> int:
    try:  # Linux: read it without changing it (os.umask would, for every thread)
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextmanager
def _removed_on_termination(tmp: list):
    """While the block runs, SIGTERM/SIGHUP remove the temporary file named in ``tmp`` and then
    end the program as they would have; where a handler is already installed (or not in the
    main thread, where handlers cannot be set) nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.getsignal(s) for s in _TERMINATING}
    ours = [s for s, handler in previous.items() if handler is signal.SIG_DFL]

    def terminate(signum, frame):
        if tmp:
            try:
                os.unlink(tmp[0])
            except OSError:
                pass
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)  # end as the signal would have

    for s in ours:
        signal.signal(s, terminate)
    try:
        yield
    finally:
        for s in ours:
            signal.signal(s, signal.SIG_DFL)


def atomic_write(path: str | os.PathLike, write: Callable[[IO], None], binary: bool = False,
                 keep: Iterable[str | os.PathLike] = ()) -> None:
    """Create or replace the file ``path`` with what ``write(stream)`` writes (UTF-8 text
    with \\n line ends, or bytes when ``binary``), by the rules in this module's docstring.
    ``keep``: paths that must not be overwritten (e.g. the input scene)."""
    target = write_target(path, keep)
    try:
        info = target.stat()
    except OSError:
        info = None
    tmp: list[str] = []
    with _removed_on_termination(tmp):
        try:
            fd, name = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
        except OSError as e:  # name the file the user asked for, not the temporary one
            raise type(e)(e.errno, e.strerror, str(path)) from None
        tmp.append(name)
        try:
            with (os.fdopen(fd, "wb") if binary
                  else os.fdopen(fd, "w", encoding="utf-8", newline="\n")) as stream:
                write(stream)
                stream.flush()
                os.fsync(stream.fileno())
            if info is None:
                os.chmod(name, 0o666 & ~_umask())
            else:
                os.chmod(name, stat.S_IMODE(info.st_mode))
                try:
                    os.chown(name, info.st_uid, info.st_gid)
                except OSError:  # only root may give a file away; the group where allowed
                    pass
            os.replace(name, target)
        except BaseException:
            try:
                os.unlink(name)
            except OSError:
                pass
            raise


def atomic_write_text(path: str | os.PathLike, text: str, keep: Iterable[str | os.PathLike] = ()) -> None:
    atomic_write(path, lambda stream: stream.write(text), keep=keep)


def atomic_write_bytes(path: str | os.PathLike, data: bytes, keep: Iterable[str | os.PathLike] = ()) -> None:
    atomic_write(path, lambda stream: stream.write(data), binary=True, keep=keep)


def open_regular(path: str | os.PathLike) -> IO[bytes]:
    """Open a file for reading in binary mode, refusing (``RefusedPath``) anything that is not
    a regular file before it could block or never end (a FIFO, a device, a folder)."""
    info = os.stat(path)
    kind = _kind(info.st_mode)
    if kind is None:  # opened without blocking, and checked again: it may have been replaced
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
        kind = _kind(os.fstat(fd).st_mode)
        if kind is None:
            if hasattr(os, "set_blocking"):
                os.set_blocking(fd, True)
            return os.fdopen(fd, "rb")
        os.close(fd)
    raise _refuse(path, f"is {kind}, not a regular file",
                  errno.EISDIR if kind == "a folder" else errno.EPERM)

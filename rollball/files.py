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

A set of files that belong together (a report's compare.json, compare.md and compare.png; a
sweep's sweep.csv, sweep.json and sweep.png) goes through ``replace_together``: every file is
written whole into a staging folder beside its target first, and only then are they renamed
into place, one after the other; a rename that fails puts back the ones before it. So the
set is replaced entirely or not at all. ``check_outputs`` makes the same checks before long
work, so that a refused folder or file costs nothing.

``open_regular`` opens a file for reading only if it is a regular file: a named pipe
would block the program forever, a device never end.
"""

from __future__ import annotations

import errno
import os
import shutil
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
        for name in tmp:  # temporary files, or staging folders (see replace_together)
            try:
                if os.path.isdir(name) and not os.path.islink(name):
                    shutil.rmtree(name, ignore_errors=True)
                else:
                    os.unlink(name)
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
                 keep: Iterable[str | os.PathLike] = (), durable: bool = True) -> None:
    """Create or replace the file ``path`` with what ``write(stream)`` writes (UTF-8 text
    with \\n line ends, or bytes when ``binary``), by the rules in this module's docstring.
    ``keep``: paths that must not be overwritten (e.g. the input scene). ``durable``: on disk
    before the rename (fsync); only files that check themselves when read (the cache's, by
    their SHA-256) skip it, as a crash may leave them empty or torn."""
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
                if durable:
                    os.fsync(stream.fileno())
            _take_mode(name, info)
            os.replace(name, target)
        except BaseException:
            try:
                os.unlink(name)
            except OSError:
                pass
            raise


def atomic_write_text(path: str | os.PathLike, text: str, keep: Iterable[str | os.PathLike] = ()) -> None:
    atomic_write(path, lambda stream: stream.write(text), keep=keep)


def atomic_write_bytes(path: str | os.PathLike, data: bytes, keep: Iterable[str | os.PathLike] = (),
                       durable: bool = True) -> None:
    atomic_write(path, lambda stream: stream.write(data), binary=True, keep=keep, durable=durable)


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


# -- sets of files replaced together --------------------------------------------------------

STAGING_PREFIX = ".rollball-staging-"


class NotReplaced(OSError):
    """A set of files was not replaced. ``strerror`` says why and what holds what: nothing of
    the set was replaced (the old files stay), and where the new files were kept, if
    anywhere (``kept``, a folder); ``filename`` names the file that failed."""

    kept: Path | None = None


def _folder(directory: str | os.PathLike) -> Path:
    """The output folder, made if missing; OSError naming it if it is not a writable folder."""
    folder = Path(directory)
    if folder.exists() and not folder.is_dir():
        raise _refuse(directory, "is a file, not a folder; nothing was written", errno.ENOTDIR)
    folder.mkdir(parents=True, exist_ok=True)
    mode = folder.stat().st_mode
    if not mode & 0o222 or not os.access(folder, os.W_OK | os.X_OK):
        raise _refuse(directory, "is a read-only folder; nothing was written", errno.EACCES)
    return folder


def check_outputs(directory: str | os.PathLike, names: Iterable[str],
                  keep: Iterable[str | os.PathLike] = ()) -> list[Path]:
    """Before long work: the folder (made if missing) and each file ``names`` in it may be
    written, and a staging folder can be made there; the targets, or ``OSError`` (naming the
    folder or file and why) if not."""
    folder = _folder(directory)
    keep = list(keep)
    targets = [write_target(folder / name, keep) for name in names]
    for parent in dict.fromkeys(t.parent for t in targets):
        shutil.rmtree(tempfile.mkdtemp(dir=parent, prefix=STAGING_PREFIX))  # OSError if it cannot
    return targets


def replace_together(directory: str | os.PathLike, files: dict[str, object],
                     keep: Iterable[str | os.PathLike] = (), kept_name: str | None = None) -> list[Path]:
    """Replace the files ``files`` (name -> str for UTF-8 text, bytes, or None to remove an old
    file of that name) in ``directory`` (made if missing) together: all of them or none.

    Each is written whole into a staging folder in ``directory`` first (by the rules of
    ``atomic_write``: permissions of a replaced file kept; read-only files, special files,
    ``keep`` refused), then the staged files are renamed into place; if a rename fails, the
    ones before it are put back. Raises ``NotReplaced`` when nothing was replaced: its message
    says so, and, when ``kept_name`` is given, the new files are kept in a new folder named
    ``kept_name-XXXX`` in ``directory`` (``NotReplaced.kept``; its message names it). Returns
    the files written."""
    folder = _folder(directory)
    keep = list(keep)
    listed = ", ".join(files)
    tmp: list[str] = []

    def failed(error: OSError, stage: str | None) -> NotReplaced:
        where = None
        if stage is not None and kept_name is not None:
            try:
                for name in os.listdir(stage):  # only the new files stay
                    if name not in files:
                        os.unlink(os.path.join(stage, name))
                where = tempfile.mkdtemp(dir=folder, prefix=f"{kept_name}-")
                os.rmdir(where)
                os.rename(stage, where)
                tmp.remove(stage)
            except OSError:
                where = None
        reason = (error.strerror or str(error)).removesuffix("; nothing was written")
        kept = (f"; the new files are in {where}" if where and os.listdir(where)
                else "; the new files were not kept")
        out = NotReplaced(error.errno or errno.EIO, f"{reason}; none of {listed} was replaced (the old "
                          f"ones, if any, are untouched){kept}", error.filename or str(folder))
        out.kept = Path(where) if where else None
        return out

    with _removed_on_termination(tmp):
        stage = None
        try:
            try:
                stage = tempfile.mkdtemp(dir=folder, prefix=STAGING_PREFIX)
                tmp.append(stage)
                moves: list[tuple[str | None, Path]] = []   # (staged file or None to remove, target)
                staged = {}
                for name, content in files.items():  # first what was computed, whatever else fails
                    if content is not None:
                        staged[name] = os.path.join(stage, name)
                        _stage(staged[name], content, folder / name)
                backups: dict[Path, str] = {}
                for name, content in files.items():
                    target = write_target(folder / name, keep)
                    beside = stage
                    if target.parent != Path(os.path.realpath(folder)):
                        # a link to another folder (maybe another file system): stage beside the file it names
                        beside = tempfile.mkdtemp(dir=target.parent, prefix=STAGING_PREFIX)
                        tmp.append(beside)
                    if target.exists():  # a second name for the old file: put back if a later rename fails
                        backups[target] = os.path.join(beside, f".old.{len(backups)}")
                        _second_name(target, backups[target])
                    if content is None:
                        moves.append((None, target))
                    elif beside == stage:
                        moves.append((staged[name], target))
                    else:
                        _stage(os.path.join(beside, target.name), content, target)
                        moves.append((os.path.join(beside, target.name), target))
            except OSError as error:
                raise failed(error, stage) from None
            done: list[tuple[str | None, Path]] = []
            try:
                for staged_file, target in moves:
                    if staged_file is not None:
                        if staged_file.startswith(stage):  # keep a copy until all are in place
                            _second_name(staged_file, staged_file + ".placed")
                        os.replace(staged_file, target)
                        if staged_file.startswith(stage):
                            os.replace(staged_file + ".placed", staged_file)
                    elif target in backups:
                        os.unlink(target)
                    done.append((staged_file, target))
            except OSError as error:
                undone = []
                for staged_file, target in reversed(done):
                    try:
                        if target in backups:
                            os.replace(backups[target], target)
                        elif staged_file is not None:
                            os.unlink(target)
                    except OSError:
                        undone.append(target.name)
                if undone:  # rare: the folder changed under us
                    raise NotReplaced(error.errno or errno.EIO,
                                      f"{error.strerror or error}; replaced and not put back: "
                                      f"{', '.join(undone)}", error.filename) from None
                raise failed(error, stage) from None
            return [target for staged_file, target in moves if staged_file is not None]
        finally:
            for name in tmp:
                shutil.rmtree(name, ignore_errors=True)


def _second_name(path, name) -> None:
    """A hard link ``name`` to the file ``path``, or a copy where links are not allowed."""
    try:
        os.link(path, name)
    except OSError:
        shutil.copy2(path, name)


def _stage(name: str, content, target: Path) -> None:
    """Write content (str or bytes) to the new file ``name`` with the permissions ``target``
    has (owner and group where allowed), or the umask's for a new file."""
    try:
        info = target.stat()
    except OSError:
        info = None
    binary = isinstance(content, (bytes, bytearray))
    fd = os.open(name, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o600)
    with (os.fdopen(fd, "wb") if binary else os.fdopen(fd, "w", encoding="utf-8", newline="\n")) as stream:
        stream.write(content)
        stream.flush()
        os.fsync(stream.fileno())
    _take_mode(name, info)


def _take_mode(name: str, info: os.stat_result | None) -> None:
    """Give a file about to replace another that one's mode (owner and group where allowed),
    or, replacing nothing (``info`` None), the umask's for a new file."""
    if info is None:
        os.chmod(name, 0o666 & ~_umask())
        return
    os.chmod(name, stat.S_IMODE(info.st_mode))
    try:
        os.chown(name, info.st_uid, info.st_gid)
    except OSError:  # only root may give a file away; the group where allowed
        pass

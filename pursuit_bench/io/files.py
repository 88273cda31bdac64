"""Writing files so that a crash never leaves a half-written one (temp file, fsync, rename), and
the lock that lets one process at a time work in a folder. Nothing heavy is imported here, so a
refusal comes before torch is loaded."""

from __future__ import annotations

import contextlib
import fcntl
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    """Replace ``path`` with ``data`` in one step (a reader sees the old file or the new one)."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    umask = os.umask(0)
    os.umask(umask)
    try:
        os.fchmod(fd, 0o666 & ~umask)  # as an ordinary new file (mkstemp makes it private)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    atomic_write_bytes(path, text.encode())


class RunBusy(ValueError):
    """Another process holds the run folder."""


#: The file of a folder that :func:`locked` locks.
LOCK_FILE = ".lock"


@contextlib.contextmanager
def locked(folder: Path) -> Iterator[None]:
    """Hold the folder's exclusive lock (``fcntl.flock`` on ``.lock``) while the block runs;
    :class:`RunBusy` at once if another process holds it. The lock is advisory (pursuit-bench's
    commands ask for it; nothing else is stopped) and dies with its process. On leaving the block
    the holder removes ``.lock``, still holding it; one killed outright leaves the file, which
    then holds nothing and is taken by the next process. Removing it is safe because a process
    that gets the lock checks that ``.lock`` is still the file it opened, and locks the new one if
    the last holder removed it in between."""
    path = folder / LOCK_FILE
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
            os.close(fd)
            raise RunBusy(f"{folder} is in use by another pursuit-bench process (pid {holder})") from None
        except BaseException:
            os.close(fd)
            raise
        if _is(path, fd):
            break
        os.close(fd)  # removed by its last holder after it was opened: a lock on no file, so again
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield
    finally:
        if _is(path, fd):
            path.unlink(missing_ok=True)
        os.close(fd)


def _is(path: Path, fd: int) -> bool:
    """Whether ``path`` names the file open as ``fd``."""
    try:
        here = os.stat(path)
    except FileNotFoundError:
        return False
    mine = os.fstat(fd)
    return (here.st_dev, here.st_ino) == (mine.st_dev, mine.st_ino)

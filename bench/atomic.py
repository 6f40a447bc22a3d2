"""Files written whole or not at all: a temporary file beside the final name, moved into place when finished.

Every output of the bench (run folders, sweeps, experiments, stage caches, recordings) is written this way, so a
reader never sees a half-written file under its final name, and an interruption leaves at most a temporary
``.<name>.<random>.part`` (removed by :func:`atomic_write` on an error or a signal)."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

#: suffix of the temporary files
TEMP_SUFFIX = ".part"

_UMASK: list[int] = []


def umask() -> int:
    """The process's umask (read once: reading it means setting it)."""
    if not _UMASK:
        m = os.umask(0o022)
        os.umask(m)
        _UMASK.append(m)
    return _UMASK[0]


def temp_path(final: Path) -> Path:
    """A fresh, empty temporary file beside ``final`` (``.<name>.<random>.part``, created with O_EXCL, with the
    permissions an ordinary open() would give)."""
    fd, tmp = tempfile.mkstemp(dir=final.parent, prefix=f".{final.name}.", suffix=TEMP_SUFFIX)
    try:
        os.fchmod(fd, 0o666 & ~umask())  # mkstemp makes 0600
    finally:
        os.close(fd)
    return Path(tmp)


def commit(tmp: Path, final: Path) -> Path:
    """Move a finished temporary file into place as ``final`` (atomic; replaces a symlink, never follows it)."""
    fd = os.open(tmp, os.O_RDONLY | os.O_NOFOLLOW)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(tmp, final)
    with contextlib.suppress(OSError):
        dfd = os.open(final.parent, os.O_RDONLY | os.O_DIRECTORY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    return final


@contextlib.contextmanager
def atomic_write(final):
    """``with atomic_write(path) as tmp: write tmp`` → renamed to ``path`` on success; removed on an error or a
    signal (KeyboardInterrupt), so nothing half-written is ever left under either name."""
    final = Path(final)
    tmp = temp_path(final)
    try:
        yield tmp
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    commit(tmp, final)

"""Files written whole or not at all: a temporary file beside the final name, moved into place when finished.

Every output of the bench (run folders, sweeps, experiments, stage caches, recordings) is written this way, so a
reader never sees a half-written file under its final name, and an interruption leaves at most a temporary
``.<name>.<random>.part`` (removed by :func:`atomic_write` on an error or a signal).  The lock files that keep two
commands from writing the same thing (:func:`take_lock`) live here too."""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import shutil
import stat
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from typing import BinaryIO

#: suffix of the temporary files
TEMP_SUFFIX = ".part"

_UMASK: list[int] = []


def open_regular(path) -> BinaryIO | None:
    """``path`` opened for binary reading if a regular file is there, or None if not (nothing, a symbolic link —
    never followed —, a FIFO, a device, a folder); never blocks (a FIFO is opened non-blocking, then refused).
    A regular file that cannot be read raises :class:`OSError`.  How every "is this file one we wrote?" check
    looks at a file before the bench replaces it."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except FileNotFoundError:
        return None
    except OSError as e:
        if e.errno == errno.ELOOP:  # a symbolic link, refused by O_NOFOLLOW
            return None
        raise
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        return None
    return os.fdopen(fd, "rb")


def read_head(path, n: int) -> bytes | None:
    """The first ``n`` bytes (fewer if the file is shorter) of the regular file at ``path`` (:func:`open_regular`),
    or None if there is none or it cannot be read."""
    try:
        fh = open_regular(path)
    except OSError:
        return None
    if fh is None:
        return None
    with fh:
        return fh.read(n)


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


def written_temp(final, write) -> Path:
    """A temporary file beside ``final`` (:func:`temp_path`) holding what ``write(fh)`` wrote into it (binary), for
    the caller to move into place (:func:`commit`, :func:`commit_new`) — several files all at once, say, where
    :func:`atomic_write` places one; on any error or signal it is removed, and none is left."""
    tmp = temp_path(Path(final))
    try:
        with open(tmp, "wb") as fh:
            write(fh)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return tmp


def save_in_temp_folder(write, prefix: str, suffix: str) -> Path:
    """Write a file that could not go where it was asked (a full disk) into the system's temporary folder instead,
    through ``write(path)``, with the mode a new file gets from the umask (not mkstemp's 0600); its path.  Raises
    :class:`OSError`, leaving no file, when it cannot be written there either."""
    fd, name = tempfile.mkstemp(prefix=prefix, suffix=suffix)
    path = Path(name)
    try:
        try:
            os.fchmod(fd, 0o666 & ~umask())
        finally:
            os.close(fd)
        write(path)
    except BaseException:
        path.unlink(missing_ok=True)
        raise
    return path


def copy_to_new(src: Path, dst: Path) -> Path:
    """Copy the file ``src`` to ``dst``, a name nothing holds (created with O_EXCL: nothing replaced, a symbolic
    link never followed), its data and its new name in the folder flushed to disk (:func:`_fsync_folder`); ``dst``.
    All or nothing: an error anywhere — the copy, either flush — or a signal removes ``dst`` again (it is this
    call's own, made O_EXCL) before the error is raised, so a caller told it failed never finds a copy there.
    Raises :class:`OSError`.  For a file that can take no name by a link or a rename (:func:`commit_new`)."""
    fd = os.open(dst, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
    try:
        with os.fdopen(fd, "wb") as out, open(src, "rb") as fh:
            shutil.copyfileobj(fh, out)
            out.flush()
            os.fsync(out.fileno())
        _fsync_folder(dst.parent)  # (inside: a name that may not survive a crash is not reported as written)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(dst)
        raise
    return dst


def _fsync_file(path: Path) -> None:
    """Flush a finished temporary file's contents to disk (never through a symbolic link)."""
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


#: what fsync (or open) of a folder fails with where the file system cannot flush or open folders at all (as
#: PostgreSQL's fsync_fname treats them): nothing to flush, not an error
FOLDER_FSYNC_UNSUPPORTED = frozenset({errno.EBADF, errno.EINVAL, errno.EACCES})


def _fsync_folder(folder: Path) -> None:
    """Flush a folder's entries (a new name in it) to disk.  Raises :class:`OSError` (naming ``folder``) when that
    fails — an I/O error: the new name may not survive a crash —, but not where the file system cannot flush or
    open folders (:data:`FOLDER_FSYNC_UNSUPPORTED`)."""
    try:
        dfd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    except OSError as e:
        if e.errno in FOLDER_FSYNC_UNSUPPORTED:
            return
        if e.filename is None:
            e.filename = str(folder)
        raise


def commit(tmp: Path, final: Path) -> Path:
    """Move a finished temporary file into place as ``final`` (atomic; replaces a symlink, never follows it)."""
    _fsync_file(tmp)
    os.replace(tmp, final)
    with contextlib.suppress(OSError):  # the rename is done and cannot be undone (an earlier file is gone, the new
        _fsync_folder(final.parent)     # one is whole): a failed flush of its name is not reported as "not written"
    return final


#: what ``os.link`` fails with on a file system without hard links (vfat, many FUSE ones): :func:`commit_new` copies
NO_HARD_LINKS = frozenset({errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP, errno.ENOSYS, errno.EMLINK})


def commit_new(temps: dict[Path, Path]) -> list[Path]:
    """Move finished temporary files into place (``temps``: final name -> temporary file), replacing nothing: all
    or none.  Each final name is taken with ``os.link`` — on a file system without hard links (:data:`NO_HARD_LINKS`)
    with a copy created O_EXCL (:func:`copy_to_new`) —, which fails (FileExistsError, naming it) if anything is
    there — a file, a folder, a dangling symbolic link — so no other program's file that appeared after a check is
    ever replaced (no check-then-rename race).  If one name is taken, or the folders' new names cannot be flushed to
    disk (:func:`_fsync_folder`), the names already placed are removed again (each only while it is still the file
    placed) and every temporary file is left as it was; once all are placed and flushed, the temporary names are
    removed."""
    placed: list[tuple[Path, tuple[int, int]]] = []  # final name, and the identity (st_dev, st_ino) placed there
    try:
        for final, tmp in temps.items():
            _fsync_file(tmp)
            try:
                os.link(tmp, final, follow_symlinks=False)
            except FileExistsError:
                raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), str(final)) from None
            except OSError as e:
                if e.errno not in NO_HARD_LINKS:
                    raise
                copy_to_new(tmp, final)
            st = os.lstat(final)
            placed.append((final, (st.st_dev, st.st_ino)))
        for folder in {final.parent for final in temps}:  # the new names on disk, or taken back out (all or none)
            _fsync_folder(folder)
    except BaseException:
        for final, identity in placed:
            with contextlib.suppress(OSError):
                st = os.lstat(final)
                if (st.st_dev, st.st_ino) == identity:  # still what we placed (its data stays under the temp name)
                    os.unlink(final)
        raise
    for tmp in temps.values():
        os.unlink(tmp)
    return [final for final, _ in placed]


@contextlib.contextmanager
def atomic_write(final):
    """``with atomic_write(path) as tmp: write tmp`` → renamed to ``path`` on success; removed on an error or a
    signal (KeyboardInterrupt), so nothing half-written is ever left under either name.  An :class:`OSError` that
    names no file (ENOSPC, EFBIG) or only the temporary one leaves naming ``path``."""
    final = Path(final)
    tmp = None
    try:
        tmp = temp_path(final)
        yield tmp
        commit(tmp, final)  # (a folder in the way fails here: the temporary file goes too)
    except BaseException as e:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        if isinstance(e, OSError) and (e.filename is None or tmp is None or e.filename == str(tmp)):
            e.filename = str(final)  # a full disk's error names no file (or a temporary one): say which failed
        raise


class LockHeld(BlockingIOError):
    """:func:`take_lock` found the lock held by another process: ``holder`` is the pid its lock file names ("" when
    it names none)."""

    def __init__(self, path, holder: str):
        super().__init__(errno.EWOULDBLOCK, "held by another process", str(path))
        self.holder = holder


class LockFailed(OSError):
    """The lock file opened, but ``flock`` on it failed (a file system without locks); errno and text as flock's."""


def lock_holder(fd: int) -> str:
    """The pid a lock file names (what :func:`take_lock` writes into it), "" if it names none or cannot be read."""
    try:
        text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
    except OSError:
        return ""
    return text if text.isdigit() else ""


#: how long (s) a process refused a lock gives its holder to write its pid into the lock file, which it does just
#: after taking the lock (the refusal or the wait then names it)
HOLDER_PID_WAIT_S = 0.5


def take_lock(lock_path: Path, wait=None) -> int:
    """Take the exclusive ``flock`` on ``lock_path`` (created, mode 0644, never followed if it is a symbolic link)
    and write this process's pid into it; returns its file descriptor (closing it releases the lock).  Held by
    another process: :class:`LockHeld` — or, with ``wait``, the lock is waited for (a signal's KeyboardInterrupt ends
    the wait) and ``wait(holder)`` is called before waiting (the holder's pid, "" if unknown): once, and again only
    for another holder — a holder that releases the lock and takes it again before this process gets it (or a lock
    file its holder removed meanwhile, :func:`release_lock`, taken afresh by the same holder) is not told twice.
    Opening the file raises as ``os.open`` does (ELOOP: a symbolic link; ENOENT: the folder is gone);
    :class:`LockFailed` when ``flock`` fails otherwise."""
    told = None  # the holder ``wait`` was last called for
    while True:
        fd = os.open(lock_path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = lock_holder(fd)
                named_by = time.monotonic() + HOLDER_PID_WAIT_S
                while not holder and time.monotonic() < named_by:  # (its holder writes its pid just after locking)
                    time.sleep(0.002)
                    holder = lock_holder(fd)
                if wait is None:
                    raise LockHeld(lock_path, holder) from None
                if holder != told:
                    wait(holder)
                    told = holder
                fcntl.flock(fd, fcntl.LOCK_EX)
        except LockHeld:
            os.close(fd)
            raise
        except OSError as e:
            os.close(fd)
            raise LockFailed(e.errno, e.strerror, str(lock_path)) from None
        except BaseException:
            os.close(fd)
            raise
        try:
            same = os.path.samestat(os.fstat(fd), os.lstat(lock_path))
        except OSError:
            same = False
        if same:
            break
        os.close(fd)  # its holder removed it (release_lock) between our open and our lock: take the new one
    with contextlib.suppress(OSError):  # the pid only names the holder to a process refused (a full disk: unnamed)
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
    return fd


def release_lock(fd: int, lock_path: Path) -> None:
    """Remove the lock file taken with :func:`take_lock` as ``fd``, then release it (a process that opened the old
    file meanwhile finds it gone once it holds the lock, and takes a new one)."""
    with contextlib.suppress(OSError):
        os.unlink(lock_path)
    os.close(fd)

"""The out folder of a run: checked before anything runs, locked while the run writes, written atomically.

* :meth:`OutFolder.open` checks the path (no NUL byte, not a file, creatable, writable), takes an exclusive
  ``fcntl.flock`` on :data:`LOCK_NAME` inside it (a second run into the same folder is refused at once), and
  refuses a folder that already holds anything unless ``force``.  With ``force`` it first checks the whole
  tree — the folder and each of its kind's subfolders, symbolic links not followed — and refuses, removing
  nothing, if anything in it is not the command's own (its :class:`FolderKind`: a run's :data:`RUN_FILES` and
  sensor<k>/ folders, a texture sweep's or an experiment's files and subfolders, leftover temporary files); only
  then does it remove the earlier files, ``record.json`` before everything else.
* Temporary files an interrupted run left (:func:`stale_temps`: killed by SIGKILL, the OOM killer or a power cut,
  with no chance to remove them) are never taken for results.  Once the lock is held no other command is writing
  into the folder, so each regular file named as the command's own temporary files are (``.<one of its
  files>.<mkstemp's 8 characters>.part``) is such a leftover; a symbolic link, a folder or any other name is not,
  and stays the user's.  A folder that holds nothing else is used without ``--force``, the leftovers removed and
  named (:meth:`OutFolder.stale_note`, which the commands print); a folder refused for holding more removes
  nothing, and its refusal names them apart from the rest.
* Every file is written under a temporary name in the folder itself (``.<name>.<random>.part``, created with
  ``O_EXCL``, so a symlink planted there is never followed) and renamed into place with ``os.replace``, which
  replaces a symlink rather than writing through it (:func:`atomic_write`).  A reader sees a file complete or not
  at all; an error or a signal while writing removes the temporary file.

The lock file stays in the folder after the run (removing it would let two runs lock two different files of
the same name); it holds the pid of the run that last locked it. A folder the command made and left holding nothing
but its lock (refused or failed before writing) is removed at close, lock and all (:func:`release_and_remove`), and
so is each folder above it that the command made (``--out a/b/c``: all three) and that is then empty — never one it
did not make.  A second command that opens the folder while the first removes it makes it again and locks it
(:class:`FolderGone`, tried :data:`VANISHED_ATTEMPTS` times, then refused saying to try again).
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

from bench.atomic import LockFailed, LockHeld, release_lock, take_lock
from bench.atomic import TEMP_SUFFIX, atomic_write, commit, read_head, temp_path  # noqa: F401 (re-exported)
from bench.errors import BenchError, escaped
from bench.scenes.limits import MAX_SENSORS

LOCK_NAME = ".biotac-bench.lock"
#: Files a run writes; ``--force`` removes only these (and leftover temporary files).
#: Every file a run writes (bench.reporting.report.write_outputs: the store, its exports, the report, the record and
#: each plot of bench.reporting.plots.scene_plots, a sliding run's forces.png and properties.png included).
RUN_FILES = ("record.json", "samples.h5", "codes.npz", "samples.csv", "report.md", "traces.png",
             "spectrogram.png", "electrode_map.png", "forces.png", "properties.png")


@dataclass(frozen=True)
class FolderKind:
    """What a command writes into its out folder: ``files`` and ``subfolders`` (each holding such files), which
    ``--force`` may replace, and ``what`` they are, for the refusal (``pass --force to replace <what>``)."""

    what: str
    files: tuple[str, ...]
    subfolders: tuple[str, ...] = ()
    #: file name -> how the command's own file of that name starts: a file there that starts otherwise (the user's
    #: own notes named report.md, say) is not the command's, and --force refuses the folder instead of removing it
    starts: tuple[tuple[str, bytes], ...] = ()

    def inner(self) -> "FolderKind":
        """The kind of one of the subfolders: the same files, no subfolders of its own."""
        return FolderKind(self.what, self.files, starts=self.starts)

    def owns(self, path: Path) -> bool:
        """Whether the file at ``path`` (one of :attr:`files`) starts as this command's own does."""
        prefix = dict(self.starts).get(path.name)
        if prefix is None or path.is_symlink():  # a link is removed, never followed: its target is never touched
            return True
        return read_head(path, len(prefix)) == prefix  # a FIFO or device of that name is not the command's


#: a scene run's folder (``biotac-bench run``): its files, and a several-sensor run's sensor<k>/ folders of them
_PNG = b"\x89PNG\r\n\x1a\n"
RUN = FolderKind("an earlier run's files", RUN_FILES, tuple(f"sensor{k}" for k in range(2, MAX_SENSORS + 1)),
                 starts=(("record.json", b"{"), ("samples.h5", b"\x89HDF\r\n\x1a\n"), ("codes.npz", b"PK"),
                         ("samples.csv", b"time_s,channel,code,status,value,unit\n"),
                         ("report.md", b"# Scene report: "))
                 + tuple((name, _PNG) for name in RUN_FILES if name.endswith(".png")))
#: one sensor<k>/ folder of a several-sensor run: a run's files, no subfolders
RUN_SENSOR = RUN.inner()


class OutDirError(BenchError, ValueError):
    """The out folder cannot be used (the message names it: :func:`folder_named`)."""


def folder_named(path, flag: str = "--out", default: bool = False, what: str = "folder") -> str:
    """How a message names an out folder (or, ``what="file"``, an out file): ``--out PATH``, the flag and the path
    as the user gave them (unquoted, as every message shows a path; :func:`~bench.errors.escaped`: one line), or,
    for the one a command chose itself because no ``flag`` was given (``default``),
    ``PATH (the default folder; --out chooses another)``."""
    shown = escaped(os.fspath(path))
    return f"{shown} (the default {what}; {flag} chooses another)" if default else f"{flag} {shown}"


class FolderGone(OutDirError):
    """The folder being made or locked was removed meanwhile (by another command that made it, as it ended)."""


#: how many times :meth:`OutFolder.open` makes and locks a folder that another command keeps removing
VANISHED_ATTEMPTS = 5


#: the name of the folder's write probe (:meth:`OutFolder._probe_writable`, :func:`writable_folder`), a temporary
#: file of every kind of folder
PROBE = "probe"
#: a temporary file's name (:func:`temp_path`): "." + the final name + "." + mkstemp's 8 random characters (lower
#: case letters, digits, "_") + :data:`TEMP_SUFFIX`
_TEMP_NAME = re.compile(r"\.(?P<final>.+)\.[a-z0-9_]{8}" + re.escape(TEMP_SUFFIX))


def _is_temp(name: str, files=RUN_FILES) -> bool:
    """Whether ``name`` is a temporary file (:func:`temp_path`) of one of ``files`` or of the write probe."""
    m = _TEMP_NAME.fullmatch(name)
    return m is not None and (m.group("final") in files or m.group("final") == PROBE)


def stale_temps(folder: Path, kind: FolderKind = RUN) -> list[str]:
    """The temporary files an interrupted run left in ``folder`` (sorted names): regular files (by lstat: never a
    symbolic link, a folder, a FIFO) named as ``kind``'s own temporary files are (:func:`_is_temp`).  Leftovers only
    while the caller holds the folder's lock: a command writing into the folder holds it too."""
    return sorted(e.name for e in os.scandir(folder)
                  if _is_temp(e.name, kind.files) and e.is_file(follow_symlinks=False))


class OutFolder:
    """A checked, locked out folder; use :meth:`open`, then :meth:`atomic` / :meth:`write_text`, then
    :meth:`close` (or use it as a context manager)."""

    def __init__(self, path: Path, lock_fd: int, flag: str = "--out", kind: FolderKind = RUN, default: bool = False):
        self.path, self._lock_fd, self.flag, self.kind = path, lock_fd, flag, kind
        #: whether the command chose this folder itself (no ``flag`` given): messages say so (:func:`folder_named`)
        self.default = default
        self._deferred_keep: tuple[str, ...] | None = None  # earlier results to remove at clear_earlier()
        #: the temporary files an interrupted run had left, removed when this command opened the folder
        self.stale: tuple[str, ...] = ()
        self._created = False  # made by this open (removed at close if it then holds nothing but the lock)
        #: every folder this open made (the folder itself and those above it), outermost first, with its identity
        #: (st_dev, st_ino): removed at close, innermost first, when the folder holds nothing but the lock
        self._made: list[tuple[Path, tuple[int, int]]] = []

    # ---- opening
    @classmethod
    def open(cls, path, force: bool = False, flag: str = "--out", kind: FolderKind = RUN,
             keep: tuple[str, ...] = (), defer_clearing: bool = False, default: bool = False) -> "OutFolder":
        """Check, create and lock ``path``; refuse it if it holds anything but ``keep`` (names of entries to leave
        alone, e.g. a cache inside it) unless ``force``, which replaces what ``kind`` wrote there before — at once,
        or, with ``defer_clearing``, only at :meth:`clear_earlier` (a long command that fails first keeps them).
        ``default``: the command chose ``path`` itself, no ``flag`` was given (messages say so)."""
        where = folder_named(path, flag, default)
        made: list[tuple[Path, tuple[int, int]]] = []
        for _ in range(VANISHED_ATTEMPTS):  # the folder removed under us (FolderGone): made again, locked again
            try:
                p = _make_folder(path, where, made)
                fd = _lock(p, where, flag)
                break
            except FolderGone:
                continue
        else:
            _remove_made(made)
            raise OutDirError(f"{where}: the folder was removed each time this command made it and went to lock it "
                              f"({VANISHED_ATTEMPTS} times; another command that made it removes it as it ends); "
                              f"try again") from None
        existed = p not in [d for d, _ in made]
        folder = cls(p, fd, flag, kind, default)
        folder._made = made
        folder._created = not existed
        try:
            folder._probe_writable()
            folder._prepare(force, keep, remove=not defer_clearing)
        except OSError as e:
            folder.close()
            raise OutDirError(f"{where}: {e.strerror or e}") from None
        except BaseException:
            folder.close()
            raise
        return folder

    def _where(self) -> str:
        return folder_named(self.path, self.flag, self.default)

    def _probe_writable(self) -> None:
        try:
            fd, name = tempfile.mkstemp(dir=self.path, prefix=f".{PROBE}.", suffix=TEMP_SUFFIX)
        except OSError as e:
            raise OutDirError(f"{self._where()}: the folder is not writable ({e.strerror or e})") from None
        os.close(fd)
        os.unlink(name)

    def clear_earlier(self) -> None:
        """Remove the earlier results that :meth:`open` with ``defer_clearing`` left in place (the tree checked
        again), just before the new ones are written; nothing if there were none or they are already gone."""
        if self._deferred_keep is not None:
            keep, self._deferred_keep = self._deferred_keep, None
            self._prepare(True, keep)

    def _prepare(self, force: bool, keep: tuple[str, ...] = (), remove: bool = True) -> None:
        """Refuse a folder that is not empty unless ``force``; with it, check the whole tree first (every entry of
        the folder and of each of ``kind``'s subfolders, symbolic links not followed) and remove nothing unless
        all of it is the command's own — then (``remove``; else at :meth:`clear_earlier`) remove ``record.json``
        first (never a stale "ok"), then the subfolders, then the rest."""
        stale = stale_temps(self.path, self.kind)
        entries = sorted(e.name for e in os.scandir(self.path)
                         if e.name != LOCK_NAME and e.name not in keep and e.name not in stale)
        if not entries:
            self._remove_stale(stale)
            return
        listed = ", ".join(entries[:6]) + (f", … ({len(entries)} entries)" if len(entries) > 6 else "")
        if not force:
            left = f"; it also holds {_stale_words(stale)}" if stale else ""
            raise OutDirError(f"{self._where()}: the folder is not empty ({listed}){left}; pass --force to replace "
                              f"{self.kind.what}, or choose a fresh folder")
        files, subfolders, foreign = _own_entries(self.path, self.kind, keep)
        sub_files: dict[str, list[str]] = {}
        for name in subfolders:
            own, nested, more = _own_entries(self.path / name, self.kind.inner())
            sub_files[name] = own
            foreign += [f"{name}/{n}" for n in nested + more]
        if foreign:
            raise OutDirError(f"{self._where()}: --force only replaces {self.kind.what}, and the folder also "
                              f"holds: {', '.join(foreign[:6])}" + (" …" if len(foreign) > 6 else ""))
        self._remove_stale(stale)  # (never results: gone at once, even when the earlier results wait for clear_earlier)
        if not remove:
            self._deferred_keep = keep
            return
        locks = []  # each subfolder locked (a writer still in one is refused) before anything is removed
        try:
            for name in subfolders:
                locks.append(_lock(self.path / name, f"{self._where()} ({name}/)", self.flag))
            self._remove([n for n in files if n == "record.json"])
            for name in subfolders:
                self._remove([f"{name}/{n}" for n in sorted(sub_files[name], key=lambda n: n != "record.json")]
                             + [f"{name}/{LOCK_NAME}"])
                try:
                    os.rmdir(self.path / name)
                except OSError as e:
                    raise OutDirError(f"{self._where()}: cannot remove {name}/ of an earlier run "
                                      f"({e.strerror or e})") from None
            self._remove([n for n in files if n != "record.json"])
        finally:
            for fd in locks:
                with contextlib.suppress(OSError):
                    os.close(fd)

    def _remove(self, names: list[str]) -> None:
        """Remove these files of an earlier run (paths relative to the folder), in this order."""
        _remove_files(self.path, names, self._where(), "of an earlier run")

    def _remove_stale(self, names: list[str]) -> None:
        """Remove the temporary files an interrupted run left (:func:`stale_temps`), noting them in :attr:`stale`."""
        self._remove(names)
        self.stale += tuple(names)

    def stale_note(self) -> str | None:
        """What the command says when it removed temporary files an interrupted run had left (None if none)."""
        if not self.stale:
            return None
        return f"note: {self._where()}: removed {_stale_words(list(self.stale))}"

    # ---- writing
    def temp_path(self, name: str) -> Path:
        """A fresh, empty temporary file in the folder for ``name`` (:func:`temp_path`)."""
        return temp_path(self.path / name)

    def commit(self, tmp: Path, name: str) -> Path:
        """Move a finished temporary file into place as ``name`` (:func:`commit`)."""
        return commit(tmp, self.path / name)

    def atomic(self, name: str):
        """``with folder.atomic("x.png") as tmp: write tmp`` → renamed to ``x.png`` on success, removed on error."""
        return atomic_write(self.path / name)

    def write_text(self, name: str, text: str) -> Path:
        with self.atomic(name) as tmp:
            tmp.write_text(text, encoding="utf-8")
        return self.path / name

    def remove_temps(self) -> None:
        """Remove temporary files this run left behind (after an error)."""
        for e in os.scandir(self.path):
            if _is_temp(e.name, self.kind.files):
                with contextlib.suppress(OSError):
                    os.unlink(e.path)

    # ---- closing
    def close(self) -> None:
        """Release the lock. A folder this command made that holds nothing but its lock (the command was refused
        or failed before writing anything) is removed, with each folder above it that this command made and that
        is then empty, so a refused command leaves no folder behind (and removes none it did not make)."""
        if self._lock_fd is None:
            return
        fd, self._lock_fd = self._lock_fd, None
        try:
            only_lock = self._created and [e.name for e in os.scandir(self.path)] == [LOCK_NAME]
        except OSError:
            only_lock = False
        if only_lock:
            release_and_remove(fd, self.path / LOCK_NAME)
            _remove_made(self._made)  # (not empty if another command has meanwhile locked it: it stays)
        else:
            with contextlib.suppress(OSError):
                os.close(fd)  # releases the flock

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _remove_files(folder: Path, names, where: str, what: str) -> None:
    """Remove these files (paths relative to ``folder``), in this order, skipping one already gone; one that cannot
    be removed is an :class:`OutDirError` naming ``where``, the file and ``what`` it is ("of an earlier run")."""
    for name in names:
        try:
            os.unlink(folder / name)
        except FileNotFoundError:
            pass
        except OSError as e:
            raise OutDirError(f"{where}: cannot remove {name} {what} ({e.strerror or e})") from None


def _stale_words(names: list[str], command: str = "run") -> str:
    """Temporary files an interrupted ``command`` left, named for a message (at most 6)."""
    shown = ", ".join(names[:6]) + (" …" if len(names) > 6 else "")
    return (f"{len(names)} temporary file{'s' if len(names) > 1 else ''} that an interrupted {command} left, killed "
            f"(or the machine down) before it could clean up, partial writes and never results: {shown}")


class OutFile:
    """A lone output file a command writes (``campaign --junit``, ``record --out``) with the lock beside it
    (``.<name>.lock``, :func:`lock_exclusively`), held from :meth:`open` to :meth:`close`: a second command writing
    the same file is refused at once, and — no other command writing it meanwhile — the temporary files of it, or
    of the files written ``beside`` it (record's CSV), that are found there (``.<name>.<random>.part``, regular
    files only, as :func:`atomic_write` names them) are what an interrupted command left, killed with no chance to
    clean up (SIGKILL, the OOM killer, a power cut): :meth:`open` removes them and :meth:`stale_note` names them.
    The file itself is written with :func:`atomic_write` (or :func:`temp_path` and a commit), so a reader never
    sees it half-written."""

    def __init__(self, path: Path, where: str, command: str):
        self.path, self.where, self.command = path, where, command
        self._lock_fd: int | None = None
        self._lock_path = path.parent / f".{path.name}.lock"
        self._made: list[tuple[Path, tuple[int, int]]] = []
        #: the temporary files an interrupted command had left, removed when this one opened the file
        self.stale: tuple[str, ...] = ()

    @classmethod
    def open(cls, path, flag: str, command: str, what: str, beside: tuple[str, ...] = (), default: bool = False,
             where: str | None = None) -> "OutFile":
        """Make ``path``'s folder (removed again at close if the command leaves it empty), take the lock and remove
        the leftovers; :class:`OutDirError` naming ``flag`` and the path if the lock is held (by another
        ``command``: ``what`` is the file, for the refusal: "this report") or the folder cannot be made.  Messages
        name the file as :func:`folder_named` does (``default``: no ``flag`` was given, the command chose it), or
        as ``where`` (what the user typed: the folder ``claims --plots`` writes its plot into)."""
        path = Path(path)
        out = cls(path, where or folder_named(path, flag, default, "file"), command)
        _make_folder(path.parent, out.where, out._made)
        try:
            out._lock_fd = lock_exclusively(out._lock_path, out.where,
                                            lambda who: f"{who} is writing {what}; wait for it to end or choose "
                                                        f"another {flag}", holder_is=f"another {command}")
            names = (path.name, *beside)
            out.stale = tuple(sorted(e.name for e in os.scandir(path.parent) if e.is_file(follow_symlinks=False)
                                     and (m := _TEMP_NAME.fullmatch(e.name)) and m.group("final") in names))
            _remove_files(path.parent, out.stale, out.where, f"(a temporary file an interrupted {command} left)")
        except BaseException:
            out.close()
            raise
        return out

    def stale_note(self) -> str | None:
        """What the command says when it removed temporary files an interrupted one had left (None if none)."""
        return f"note: {self.where}: removed {_stale_words(list(self.stale), self.command)}" if self.stale else None

    def close(self) -> None:
        """Release and remove the lock, then each folder :meth:`open` made that is left empty (nothing written)."""
        if self._lock_fd is not None:
            fd, self._lock_fd = self._lock_fd, None
            release_and_remove(fd, self._lock_path)
        _remove_made(self._made)
        self._made = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _lock(folder: Path, where: str, flag: str) -> int:
    """Take the exclusive, non-blocking ``flock`` on ``folder``'s :data:`LOCK_NAME`; returns its file descriptor,
    or raises :class:`OutDirError` naming ``where``."""
    return lock_exclusively(folder / LOCK_NAME, where, lambda who: f"{who} is writing into this folder; wait for "
                                                                   f"it to end or choose another {flag}")


def lock_exclusively(lock_path: Path, where: str, busy, holder_is: str = "another run") -> int:
    """Take the exclusive, non-blocking lock on ``lock_path`` (:func:`~bench.atomic.take_lock`: created, never
    followed if it is a symbolic link, this process's pid written into it); returns its file descriptor (closing it
    releases the lock), or raises :class:`OutDirError` naming ``where`` — ``busy(who)`` says what to do when another
    process holds it (``who``: ``holder_is`` and its pid)."""
    try:
        return take_lock(lock_path)
    except LockHeld as e:
        who = f"{holder_is} (pid {e.holder})" if e.holder else holder_is
        raise OutDirError(f"{where}: {busy(who)}") from None
    except LockFailed as e:
        raise OutDirError(f"{where}: cannot lock {lock_path} ({e.strerror or e})") from None
    except OSError as e:
        if e.errno == errno.ELOOP:
            raise OutDirError(f"{where}: {lock_path.name} is a symbolic link; remove it") from None
        gone = FolderGone if e.errno == errno.ENOENT else OutDirError  # (OutFolder.open makes it again)
        raise gone(f"{where}: {lock_path.parent} is not writable ({e.strerror or e})") from None


#: remove a lock file taken with :func:`lock_exclusively`, then release it (:func:`~bench.atomic.release_lock`)
release_and_remove = release_lock


def _own_entries(folder: Path, kind: FolderKind, keep: tuple[str, ...] = ()) -> tuple[list[str], list[str], list[str]]:
    """``folder``'s entries (its lock and ``keep`` aside) sorted into ``kind``'s files (and their temporary
    files), ``kind``'s subfolders (real folders, not symbolic links) and anything else (foreign); by lstat."""
    files, subfolders, foreign = [], [], []
    for e in sorted(os.scandir(folder), key=lambda e: e.name):
        if e.name == LOCK_NAME or e.name in keep:
            continue
        real_dir = e.is_dir(follow_symlinks=False)
        if e.name in kind.subfolders and real_dir:
            subfolders.append(e.name)
        elif _is_temp(e.name, kind.files) and e.is_file(follow_symlinks=False):
            files.append(e.name)
        elif e.name in kind.files and not real_dir:
            if kind.owns(folder / e.name):
                files.append(e.name)
            else:
                foreign.append(f"{e.name} (not as this command writes it)")
        else:
            foreign.append(e.name)
    return files, subfolders, foreign


def fresh_folder(base: Path, force: bool = False, flag: str = "--out", kind: FolderKind = RUN,
                 defer_clearing: bool = False) -> OutFolder:
    """The default out folder: ``base`` if it is absent or empty (or holds only the temporary files an interrupted
    run left, which opening it removes), else ``base-2``, ``base-3``, … — the first that is free and not locked by
    another run (with ``force``: ``base``, its earlier files replaced)."""
    last = None
    for n in range(1, 1000):
        p = base if n == 1 else base.with_name(f"{base.name}-{n}")
        if not force and p.is_dir() and _holds_more_than_leftovers(p, kind):
            continue
        try:
            return OutFolder.open(p, force=force, flag=flag, kind=kind, defer_clearing=defer_clearing, default=True)
        except OutDirError as e:
            last = e
            if "is writing into this folder" in str(e) or "not empty" in str(e):
                continue
            raise
    raise last or OutDirError(f"{folder_named(base, flag, default=True)}: no free folder next to it")


def _holds_more_than_leftovers(folder: Path, kind: FolderKind) -> bool:
    """Whether ``folder`` holds anything but its lock and the temporary files an interrupted run left
    (:func:`stale_temps`; :meth:`OutFolder.open` removes those, so a folder holding only them is free)."""
    stale = stale_temps(folder, kind)
    with os.scandir(folder) as entries:  # closed here: any() stops at the first result, the listing unfinished
        return any(e.name != LOCK_NAME and e.name not in stale for e in entries)


def _make_folder(path, where: str, made: list | None = None) -> Path:
    """Create the folder ``path`` (named as ``where`` in errors: :func:`folder_named`) after checking it: no NUL
    byte, not empty, not a broken symbolic link, not a file, creatable.  Each folder it creates (``path`` and those
    above it), outermost first, is appended to ``made`` with its identity (st_dev, st_ino); on an error those are
    removed again.  A folder on the way that vanishes meanwhile (another command removing it as it ends) raises
    :class:`FolderGone`."""
    raw = os.fspath(path)
    if "\x00" in raw:
        raise OutDirError(f"{where}: the path contains a NUL byte")
    if not raw.strip():
        raise OutDirError(f"{where}: the path is empty")
    p = Path(raw)
    made = [] if made is None else made
    new: list[tuple[Path, tuple[int, int]]] = []
    try:
        if p.is_symlink() and not p.exists():
            raise OutDirError(f"{where}: is a broken symbolic link")
        if p.exists() and not p.is_dir():
            raise OutDirError(f"{where}: is a file, not a folder")
        for d in [*reversed(p.parents), p]:
            try:
                os.mkdir(d)
            except FileNotFoundError:
                if d.parent.is_dir():  # it is there, yet refuses folders (/proc): not a race
                    raise
                raise FolderGone(f"{where}: cannot create the folder: {d.parent} was removed meanwhile") from None
            except OSError as e:
                if d.is_dir():  # there already (EEXIST; or EACCES, EROFS for a folder there that we cannot write)
                    continue
                if isinstance(e, FileExistsError):  # a file (or a link to none) where the folder should be
                    raise OutDirError(f"{where}: is a file, not a folder" if d == p else
                                      f"{where}: cannot create the folder: a part of the path is a file") from None
                raise
            st = os.lstat(d)
            new.append((d, (st.st_dev, st.st_ino)))
    except NotADirectoryError:
        _remove_made(new)
        raise OutDirError(f"{where}: cannot create the folder: a part of the path is a file") from None
    except OutDirError:
        _remove_made(new)
        raise
    except OSError as e:
        _remove_made(new)
        raise OutDirError(f"{where}: cannot create the folder: {e.strerror or e}") from None
    made += new
    return p


def _remove_made(made: list[tuple[Path, tuple[int, int]]]) -> None:
    """Remove the folders ``made`` (as :func:`_make_folder` listed them), innermost first: each that is still the
    one made (same identity) and empty; a folder gone or replaced meanwhile is skipped; the first that is not empty
    stops the removal (those above it hold it)."""
    for d, identity in reversed(made):
        try:
            st = os.lstat(d)
        except OSError:
            continue
        if (st.st_dev, st.st_ino) != identity:
            continue
        try:
            os.rmdir(d)
        except OSError:
            return


@contextlib.contextmanager
def made_folders():
    """A list for :func:`writable_folder` (``made=``) to note the folders it creates in; if the block ends in an
    error (the command refused, failed or stopped), each of them still empty is removed, innermost first, as
    :func:`_remove_made` does (never one the command did not make, nor one replaced meanwhile), so a command refused
    after checking its folders leaves none behind.  A command that ran keeps them (a stage cache is kept across
    runs, even one a full disk left empty)."""
    made: list[tuple[Path, tuple[int, int]]] = []
    try:
        yield made
    except BaseException:
        _remove_made(made)
        raise


def writable_folder(path, flag: str = "--out", made: list | None = None, default: bool = False) -> Path:
    """Check a shared folder before a long job runs (an experiment's stage cache, which runs share on purpose):
    :func:`_make_folder`'s checks and a write probe — :class:`OutDirError` naming ``flag`` otherwise (the folders it
    made for the probe removed again). No lock, nothing refused or removed (each file goes in under a temporary
    name, renamed into place).  ``made`` (:func:`made_folders`): where the folders it creates are noted, to be
    removed if the command ends leaving them empty.  ``default``: the command chose ``path`` itself, no ``flag`` was
    given (messages say so, :func:`folder_named`)."""
    new: list[tuple[Path, tuple[int, int]]] = []
    where = folder_named(path, flag, default)
    p = _make_folder(path, where, new)
    try:
        fd, name = tempfile.mkstemp(dir=p, prefix=f".{PROBE}.", suffix=TEMP_SUFFIX)
        os.close(fd)
        os.unlink(name)
    except OSError as e:
        _remove_made(new)
        raise OutDirError(f"{where}: the folder is not writable ({e.strerror or e})") from None
    if made is not None:
        made += new
    return p

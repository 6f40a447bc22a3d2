"""A recording is placed without hard links (a copy, created O_EXCL), and one refused its place (a file came at
--out meanwhile) is kept under a name of its own even where the folder refuses a hard link and a rename: copied to
its kept name (``NAME.kept-<digits>.npz``), renamed there when a full disk refuses the copy, else copied into the
system's temporary folder, and its temporary file removed, so the next record, which removes temporary files as an
interrupted one's leftovers, never removes its data; the error names where it is, each path escaped (one line).

The folder's refusals are real errors injected at the system calls (``os.link``, ``os.rename``; for a folder gone
read-only, also creating and removing files in it), armed when record first tries to place its files."""

import errno
import os
import tempfile
from pathlib import Path

import pytest

from bench.atomic import TEMP_SUFFIX
from bench.tests.test_record_race import _assert_a_whole_recording, _kept, _record

pytestmark = pytest.mark.unit


class _Refusing:
    """From the first ``os.link`` on (record placing its files), ``folder`` refuses hard links (EPERM, as a file
    system without them), and, with an errno each, renames (``rename``), new files (``create``: ENOSPC, a full disk;
    EROFS, a folder remounted read-only meanwhile) and the removal of temporary files (``remove``)."""

    def __init__(self, monkeypatch, folder: Path, rename=None, create=None, remove=None):
        self.folder, self.armed = folder, False
        real_link, real_rename, real_open, real_unlink = os.link, os.rename, os.open, os.unlink

        def refused(code, path):
            return OSError(code, os.strerror(code), os.fspath(path))

        def link(src, dst, *args, **kw):
            self.armed = True
            if self._in_folder(dst):
                raise refused(errno.EPERM, dst)
            return real_link(src, dst, *args, **kw)

        def rename_(src, dst, *args, **kw):
            if self.armed and rename and self._in_folder(dst):
                raise refused(rename, dst)
            return real_rename(src, dst, *args, **kw)

        def open_(path, flags, *args, **kw):
            if self.armed and create and flags & os.O_CREAT and self._in_folder(path):
                raise refused(create, path)
            return real_open(path, flags, *args, **kw)

        def unlink(path, *args, **kw):
            if self.armed and remove and self._in_folder(path) and os.fspath(path).endswith(TEMP_SUFFIX):
                raise refused(remove, path)
            return real_unlink(path, *args, **kw)

        for name, f in (("link", link), ("rename", rename_), ("open", open_), ("unlink", unlink)):
            monkeypatch.setattr(os, name, f)

    def _in_folder(self, path) -> bool:
        return Path(os.fsdecode(path)).parent == self.folder


def test_without_hard_links_a_recording_is_placed_by_a_copy(tmp_path, monkeypatch, capsys):
    """A file system without hard links: the files are copied to their names (created O_EXCL, still replacing
    nothing), not refused their place and kept aside."""
    out = tmp_path / "r.npz"
    _Refusing(monkeypatch, tmp_path)
    assert _record(monkeypatch, out, "--csv") == 0
    assert capsys.readouterr().err == ""
    _assert_a_whole_recording(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv", "r.npz"]


def test_without_hard_links_still_all_or_none(tmp_path, monkeypatch, capsys):
    """The CSV's name taken meanwhile: the NPZ already copied into place is taken back out (it is still the copy
    placed), and both are kept aside."""
    out, beside = tmp_path / "r.npz", tmp_path / "r.csv"
    _Refusing(monkeypatch, tmp_path)
    assert _record(monkeypatch, out, "--csv", meanwhile=lambda: beside.write_text("theirs\n")) == 2
    assert f"{beside} appeared during the recording" in capsys.readouterr().err
    assert not out.exists() and beside.read_text() == "theirs\n"
    kept = _kept(tmp_path)
    assert sorted(kept) == ["r.csv", "r.npz"]
    _assert_a_whole_recording(kept["r.npz"])


def test_a_copy_refused_by_a_full_disk_is_kept_by_a_rename(tmp_path, monkeypatch, capsys):
    out = tmp_path / "r.npz"
    _Refusing(monkeypatch, tmp_path, create=errno.ENOSPC)
    assert _record(monkeypatch, out) == 2
    err = capsys.readouterr().err
    kept = _kept(tmp_path)
    _assert_a_whole_recording(kept["r.npz"])
    assert err == (f"error: --out {out}: cannot put the recording in place: [Errno {errno.ENOSPC}] No space left on "
                   f"device: '{out}'; the recording is kept as {kept['r.npz']} (rename it to use it)\n")


def test_without_links_or_renames_the_recording_is_copied_to_its_kept_names(tmp_path, monkeypatch, capsys):
    folder = tmp_path / "a\nb"  # a line break in the path: shown escaped, the error one line
    folder.mkdir()
    out = folder / "r.npz"
    _Refusing(monkeypatch, folder, rename=errno.EACCES)
    assert _record(monkeypatch, out, "--csv", meanwhile=lambda: out.write_text("theirs")) == 2
    err = capsys.readouterr().err
    kept = _kept(folder)  # (no temporary file left)
    assert sorted(kept) == ["r.csv", "r.npz"] and out.read_text() == "theirs"
    _assert_a_whole_recording(kept["r.npz"])
    shown = {name: str(p).replace("\n", "\\n") for name, p in kept.items()}
    assert err.count("\n") == 1 and f"kept as {shown['r.npz']} and {shown['r.csv']} (rename it to use it)\n" in err


@pytest.mark.parametrize("removable", [True, False])
def test_a_folder_refusing_new_names_keeps_it_in_the_temporary_folder(tmp_path, monkeypatch, capsys, removable):
    """A folder that refuses new names but lets files be removed (a quota reached: EDQUOT) keeps no temporary file;
    one gone read-only (EROFS) keeps it, and the error says it is a copy, which the next record removes."""
    folder, system_temp = tmp_path / "rec", tmp_path / "system-temp"
    folder.mkdir()
    system_temp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(system_temp))
    out = folder / "r.npz"
    code = errno.EDQUOT if removable else errno.EROFS
    _Refusing(monkeypatch, folder, rename=code, create=code, remove=None if removable else code)
    assert _record(monkeypatch, out, meanwhile=lambda: out.write_text("theirs")) == 2
    err = capsys.readouterr().err
    [copy] = system_temp.iterdir()
    assert copy.name.startswith("r.kept-") and copy.suffix == ".npz"
    _assert_a_whole_recording(copy)
    left = [p for p in folder.iterdir() if p.name.endswith(TEMP_SUFFIX)]
    if removable:
        assert not left and err.endswith(f"; the recording is kept as {copy} (rename it to use it)\n")
    else:
        assert f"kept as {copy}; the temporary file {left[0]}, a copy, stays (the next record there removes it)" in err
    assert err.count("\n") == 1


def test_no_copy_anywhere_names_the_temporary_file_as_temporary(tmp_path, monkeypatch, capsys):
    folder = tmp_path / "rec"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "no-such-folder"))
    out = folder / "r.npz"
    _Refusing(monkeypatch, folder, rename=errno.EROFS, create=errno.EROFS, remove=errno.EROFS)
    assert _record(monkeypatch, out, meanwhile=lambda: out.write_text("theirs")) == 2
    err = capsys.readouterr().err
    [left] = [p for p in folder.iterdir() if p.name.endswith(TEMP_SUFFIX)]
    _assert_a_whole_recording(left)
    assert (f"kept as {left}; {left} is a temporary name, which the next record into that folder removes as an "
            f"interrupted one's, and no copy could be made (No such file or directory)") in err

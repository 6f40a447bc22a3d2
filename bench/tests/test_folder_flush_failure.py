"""A folder whose new name cannot be flushed to disk (bench.atomic._fsync_folder): what each way of placing a file
does then.  copy_to_new and commit_new have made nothing yet that cannot be taken back, so they fail and leave
nothing new behind; commit (atomic_write) has already replaced the earlier file, so it does not say "not written" of
a whole file that is there.

A real fsync failure (EIO from the disk) cannot be provoked from a test, so ``os.fsync`` is replaced for folder
file descriptors only; a file's own fsync stays the real one."""

from __future__ import annotations

import errno
import os
import stat

import pytest

from bench.atomic import TEMP_SUFFIX, atomic_write, commit_new, copy_to_new


def _folder_fsync_fails(monkeypatch, error: BaseException) -> list[int]:
    """``os.fsync`` raising ``error`` for a folder (every other fsync the real one); the folders' inodes it was
    asked to flush, in order."""
    real = os.fsync
    asked: list[int] = []

    def fsync(fd):
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            asked.append(st.st_ino)
            raise error
        real(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    return asked


def _src(tmp_path):
    src = tmp_path / "src" / "data.npz"
    src.parent.mkdir()
    src.write_bytes(b"a whole recording")
    return src


def test_copy_to_new_leaves_no_copy_when_the_folder_cannot_be_flushed(tmp_path, monkeypatch):
    src, dst = _src(tmp_path), tmp_path / "data.npz"
    asked = _folder_fsync_fails(monkeypatch, OSError(errno.EIO, os.strerror(errno.EIO)))
    with pytest.raises(OSError) as e:
        copy_to_new(src, dst)
    assert asked == [tmp_path.stat().st_ino]  # the folder the copy went into was the one asked
    assert e.value.errno == errno.EIO and e.value.filename == str(tmp_path)
    assert not dst.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["src"]
    assert src.read_bytes() == b"a whole recording"


def test_copy_to_new_leaves_no_copy_when_a_signal_stops_the_folder_flush(tmp_path, monkeypatch):
    src, dst = _src(tmp_path), tmp_path / "data.npz"
    _folder_fsync_fails(monkeypatch, KeyboardInterrupt())
    with pytest.raises(KeyboardInterrupt):
        copy_to_new(src, dst)
    assert not dst.exists()


@pytest.mark.parametrize("code", [errno.EINVAL, errno.EBADF, errno.EACCES])  # (as PostgreSQL ignores them)
def test_copy_to_new_places_the_copy_where_the_file_system_cannot_flush_folders(tmp_path, monkeypatch, code):
    src, dst = _src(tmp_path), tmp_path / "data.npz"
    asked = _folder_fsync_fails(monkeypatch, OSError(code, os.strerror(code)))
    assert copy_to_new(src, dst) == dst
    assert asked and dst.read_bytes() == b"a whole recording"


def test_commit_new_takes_every_name_back_when_the_folder_cannot_be_flushed(tmp_path, monkeypatch):
    temps = {}
    for name in ("a.npz", "a.csv"):
        temps[tmp_path / name] = tmp_path / f".{name}.x{TEMP_SUFFIX}"
        temps[tmp_path / name].write_text(f"new {name}")
    _folder_fsync_fails(monkeypatch, OSError(errno.EIO, os.strerror(errno.EIO)))
    with pytest.raises(OSError) as e:
        commit_new(temps)
    assert e.value.errno == errno.EIO
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(tmp.name for tmp in temps.values())
    assert all(tmp.read_text() == f"new {final.name}" for final, tmp in temps.items())


def test_atomic_write_keeps_the_replaced_file_when_the_folder_cannot_be_flushed(tmp_path, monkeypatch):
    final = tmp_path / "trials.json"
    final.write_text("the earlier file")
    asked = _folder_fsync_fails(monkeypatch, OSError(errno.EIO, os.strerror(errno.EIO)))
    with atomic_write(final) as tmp:
        tmp.write_text("the new file")
    assert asked == [tmp_path.stat().st_ino]
    assert final.read_text() == "the new file" and [p.name for p in tmp_path.iterdir()] == ["trials.json"]

"""The out folder's own folders: a command that made ``--out a/b/c`` and wrote nothing removes every folder it made
at close, and none it did not make; a second command opening the folder while the first removes it gets the folder
(or, if it keeps vanishing, a message saying so), never "not writable"."""

import fcntl
import os

import pytest

from bench.reporting import outdir
from bench.reporting.outdir import LOCK_NAME, OutDirError, OutFolder

pytestmark = pytest.mark.unit


def test_a_nested_folder_the_command_made_is_removed_up_to_the_first_it_did_not_make(tmp_path):
    """`--out a/b/c` with none of them there: close removes c, b and a (c alone was removed before)."""
    OutFolder.open(tmp_path / "a" / "b" / "c").close()
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "user").mkdir()  # the user's: stays, as does everything above it
    OutFolder.open(tmp_path / "user" / "x" / "y").close()
    assert [p.name for p in tmp_path.iterdir()] == ["user"] and list((tmp_path / "user").iterdir()) == []
    OutFolder.open(tmp_path / "p" / "q" / ".." / "r").close()  # made p, p/q and p/r: all three removed
    assert [p.name for p in tmp_path.iterdir()] == ["user"]


def test_a_made_folder_that_something_else_filled_meanwhile_stays(tmp_path):
    """A folder the command made but that holds another file by close (the user's) is not removed, nor any above."""
    with OutFolder.open(tmp_path / "a" / "b" / "c"):
        (tmp_path / "a" / "notes.txt").write_text("mine")
    assert [p.name for p in (tmp_path / "a").iterdir()] == ["notes.txt"]


def test_a_folder_removed_by_the_command_that_made_it_just_before_the_lock_is_made_again(tmp_path, monkeypatch):
    """The first command closes (removing a/b, which it made) after the second has made sure of the folder but
    before it opens the lock file there: the second makes the folders again and runs (it was refused "not
    writable"); at its close it removes them, as it made them."""
    first = OutFolder.open(tmp_path / "a" / "b")
    real_lock, ends = outdir._lock, [first]

    def first_ends_then_lock(folder, where, flag):
        if ends:
            ends.pop().close()
            assert not (tmp_path / "a").exists()
        return real_lock(folder, where, flag)

    monkeypatch.setattr(outdir, "_lock", first_ends_then_lock)
    second = OutFolder.open(tmp_path / "a" / "b")
    assert not ends and (tmp_path / "a" / "b" / LOCK_NAME).read_text() == f"{os.getpid()}\n"
    second.close()
    assert list(tmp_path.iterdir()) == []


def test_a_folder_removed_between_opening_its_lock_file_and_locking_it_is_made_again(tmp_path, monkeypatch):
    """The first command ends between the second's open of the lock file and its flock: the flock then holds a
    removed file in a removed folder; the second takes a new lock in the folder made again."""
    first = OutFolder.open(tmp_path / "a")
    real_flock, ends = fcntl.flock, [first]

    def first_ends_then_flock(fd, op):
        if ends:
            ends.pop().close()
            assert not (tmp_path / "a").exists()
        return real_flock(fd, op)

    monkeypatch.setattr(fcntl, "flock", first_ends_then_flock)
    with OutFolder.open(tmp_path / "a") as second:
        assert not ends and os.path.samestat(os.fstat(second._lock_fd), os.lstat(tmp_path / "a" / LOCK_NAME))
    assert list(tmp_path.iterdir()) == []


def test_a_parent_removed_while_the_folders_are_being_made_is_made_again(tmp_path, monkeypatch):
    """The first command removes a (which it made) just after the second found a there and before it makes a/b."""
    first = OutFolder.open(tmp_path / "a")
    real_mkdir, ends = os.mkdir, [first]

    def first_ends_then_mkdir(path, *args, **kw):
        if ends and os.fspath(path).endswith(os.sep + "b"):
            ends.pop().close()
        return real_mkdir(path, *args, **kw)

    monkeypatch.setattr(os, "mkdir", first_ends_then_mkdir)
    with OutFolder.open(tmp_path / "a" / "b"):
        assert not ends and (tmp_path / "a" / "b" / LOCK_NAME).exists()
    assert list(tmp_path.iterdir()) == []


def test_a_folder_that_keeps_vanishing_is_refused_saying_to_try_again(tmp_path, monkeypatch):
    """If the folder is removed before every attempt to lock it, the command gives up with a message saying why and
    what to do (not "not writable"), and leaves none of the folders it made."""
    real_lock = outdir._lock

    def removed_each_time(folder, where, flag):
        os.rmdir(folder)
        return real_lock(folder, where, flag)

    monkeypatch.setattr(outdir, "_lock", removed_each_time)
    with pytest.raises(OutDirError) as e:
        OutFolder.open(tmp_path / "a" / "b")
    message = str(e.value)
    assert message.startswith(f"--out {tmp_path / 'a' / 'b'}: ") and "try again" in message, message
    assert "removed" in message and "not writable" not in message, message
    assert list(tmp_path.iterdir()) == []


def test_a_folder_the_user_put_in_place_of_one_the_command_made_is_not_removed(tmp_path):
    """The user moved the command's folder into a new a/ of their own while it ran: close removes the command's
    (empty) folder, not the user's a/, though it is empty by then and stands where the command made one."""
    with OutFolder.open(tmp_path / "a" / "b"):
        (tmp_path / "a").rename(tmp_path / "old")
        (tmp_path / "a").mkdir()
        (tmp_path / "old" / "b").rename(tmp_path / "a" / "b")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "old"] and list((tmp_path / "a").iterdir()) == []


def test_a_parent_that_is_there_but_refuses_a_folder_is_not_taken_for_a_race(tmp_path, monkeypatch):
    """mkdir saying "no such file" while the parent is there (as /proc does) is the answer, not a folder removed
    meanwhile: refused at once as "cannot create the folder", none of the folders made left behind."""
    real_mkdir, tries = os.mkdir, []

    def refuses_c(path, *args, **kw):
        if os.fspath(path).endswith(os.sep + "c"):
            tries.append(path)
            raise FileNotFoundError(2, "No such file or directory", os.fspath(path))
        return real_mkdir(path, *args, **kw)

    monkeypatch.setattr(os, "mkdir", refuses_c)
    with pytest.raises(OutDirError, match=r": cannot create the folder: No such file or directory$"):
        OutFolder.open(tmp_path / "a" / "b" / "c")
    assert len(tries) == 1 and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv, made, refused", [
    (["claims", "--quick", "--only", "vibration", "--plots", "{tmp}/p/q", "--workers", "2"], "p",
     "--workers and --scheduler go with --seeds"),
    (["explore", "{quick}", "--out", "{tmp}/out", "--cache", "{tmp}/c/d", "--scheduler", "tcp://127.0.0.1:1",
      "--workers", "2"], "c", "--workers 2 sizes the LocalCluster"),
])
def test_a_folder_a_command_made_for_plots_or_a_cache_is_removed_when_it_is_refused_after(argv, made, refused,
                                                                                          tmp_path, capsys):
    """``claims --plots a/b`` and ``explore --cache a/b`` check (and so make) their folders before anything runs; a
    refusal found after that left them behind, empty.  Each folder the command made is removed again, as --out's are;
    one the user had made stays (it is not the command's)."""
    from bench.cli import main as cli
    from bench.paths import FIXTURES

    quick = FIXTURES / "experiments" / "quick.toml"
    args = [a.replace("{tmp}", str(tmp_path)).replace("{quick}", str(quick)) for a in argv]
    assert cli.main(args) == 2
    assert refused in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
    (tmp_path / made).mkdir()
    assert cli.main(args) == 2
    assert [p.name for p in tmp_path.iterdir()] == [made] and list((tmp_path / made).iterdir()) == []


def test_made_folders_removes_only_after_an_error_and_only_empty_ones(tmp_path):
    """made_folders: a block that ends well keeps the folders it made, even empty (a stage cache is kept across runs);
    one that ends in an error removes those still empty, and keeps one it wrote into."""
    with outdir.made_folders() as made:
        outdir.writable_folder(tmp_path / "kept" / "empty", "--cache", made)
    with pytest.raises(RuntimeError), outdir.made_folders() as made:
        outdir.writable_folder(tmp_path / "c" / "d", "--cache", made)
        (tmp_path / "c" / "d" / "entry").write_text("x")
        outdir.writable_folder(tmp_path / "e" / "f", "--plots", made)
        raise RuntimeError("refused later")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c", "kept"]
    assert (tmp_path / "kept" / "empty").is_dir() and (tmp_path / "c" / "d" / "entry").exists()

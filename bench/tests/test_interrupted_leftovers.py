"""A run killed with no chance to clean up (SIGKILL, the OOM killer, a power cut) leaves its temporary files
(``.<name>.<random>.part``) in the out folder.  The next command into that folder says what it found and that an
interrupted run left it, removes those files when nothing else is there (no --force needed: they are never
results), names them apart from the rest when it refuses the folder, and never removes or follows anything the
user made (a link, a folder, another name)."""

import gc
import os
import signal
import subprocess
import sys
import time
import warnings

import pytest

from bench.reporting.outdir import LOCK_NAME, OutDirError, OutFolder, FolderKind, fresh_folder, stale_temps, temp_path
from bench.tests.cli_runs import run_cli

pytestmark = pytest.mark.unit

LEFT = (".samples.h5.9vq5khgi.part", ".traces.png.abcd_123.part")  # as mkstemp names them: 8 characters


def _interrupted_run(folder, names=LEFT) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / LOCK_NAME).write_text("12345\n")  # the killed run's pid: its flock went with it
    for name in names:
        (folder / name).write_bytes(b"\x89HDF half written")


def _names(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_a_run_killed_mid_write_leaves_temporary_files_the_next_run_names_and_removes(tmp_path):
    """The real thing: ``run`` killed with SIGKILL while samples.h5 streams under its temporary name; the next
    ``run --out`` into the folder needs no --force, says which files it removed and why, and writes every result."""
    out = tmp_path / "o"
    for _ in range(5):  # (a kill that comes after the run ended leaves nothing to find: tried again)
        proc = subprocess.Popen([sys.executable, "-m", "bench.cli", "run", "press_hold", "--out", str(out),
                                 "--quiet", "--no-plots"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and proc.poll() is None and not (out.is_dir() and stale_temps(out)):
            time.sleep(0.005)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        if out.is_dir() and stale_temps(out):
            break
        subprocess.run(["rm", "-rf", str(out)], check=True)
    left = stale_temps(out)
    assert left and all(n.startswith(".samples.h5.") for n in left), _names(out)
    assert "record.json" not in _names(out)
    r = run_cli("run", "press_hold", "--out", out, "--quiet", "--no-plots")
    assert r.returncode == 0, r.stderr
    note = [line for line in r.stderr.splitlines() if line.startswith("note: ")]
    assert len(note) == 1 and "interrupted run" in note[0] and all(n in note[0] for n in left), r.stderr
    assert not stale_temps(out) and not [n for n in _names(out) if n.endswith(".part")]
    assert {"record.json", "samples.h5", "report.md"} <= set(_names(out))


def test_a_folder_holding_only_an_interrupted_runs_files_is_used_without_force(tmp_path):
    out = tmp_path / "o"
    _interrupted_run(out)
    with OutFolder.open(out) as folder:
        assert folder.stale == LEFT
        note = folder.stale_note()
    assert note.startswith(f"note: --out {out}: removed 2 temporary files that an interrupted run left")
    assert all(n in note for n in LEFT) and "never results" in note
    assert _names(out) == [LOCK_NAME]


def test_a_folder_with_no_leftovers_says_nothing(tmp_path):
    with OutFolder.open(tmp_path / "o") as folder:
        assert folder.stale == () and folder.stale_note() is None


def test_a_refused_folder_names_the_leftovers_apart_and_removes_nothing(tmp_path):
    out = tmp_path / "o"
    _interrupted_run(out)
    (out / "notes.txt").write_text("mine")
    before = _names(out)
    with pytest.raises(OutDirError) as e:
        OutFolder.open(out)
    message = str(e.value)
    assert "not empty (notes.txt); it also holds 2 temporary files that an interrupted run left" in message
    assert all(n in message for n in LEFT) and "--force" in message
    assert _names(out) == before


@pytest.mark.parametrize("lookalike", [".report.md.old.part",  # not mkstemp's 8 random characters
                                       ".notes.txt.abcdefgh.part",  # not one of a run's files
                                       ".report.md.ABCDEFGH.part",  # mkstemp makes lower case only
                                       "link", "folder"])
def test_nothing_the_user_made_is_taken_for_a_leftover(tmp_path, lookalike):
    """A symbolic link or a folder named as a temporary file, or a file named almost so, is the user's: the folder
    is refused (with --force too), the link's target untouched, everything still there."""
    out, target = tmp_path / "o", tmp_path / "precious.txt"
    _interrupted_run(out)
    target.write_text("keep me")
    if lookalike == "link":
        (out / ".report.md.zzzzzzzz.part").symlink_to(target)
    elif lookalike == "folder":
        (out / ".report.md.zzzzzzzz.part").mkdir()
    else:
        (out / lookalike).write_text("mine")
    before = _names(out)
    for force in (False, True):
        with pytest.raises(OutDirError):
            OutFolder.open(out, force=force)
        assert _names(out) == before
    assert target.read_text() == "keep me"


def test_force_replaces_an_interrupted_runs_results_and_leftovers_and_names_the_leftovers(tmp_path):
    out = tmp_path / "o"
    _interrupted_run(out)
    (out / "codes.npz").write_bytes(b"PK earlier")  # a result the killed run had already written
    with OutFolder.open(out, force=True) as folder:
        assert folder.stale == LEFT and folder.stale_note()
    assert _names(out) == [LOCK_NAME]


def test_the_default_folder_is_reused_when_it_holds_only_leftovers_and_never_taken_from_a_live_run(tmp_path):
    base = tmp_path / "press-hold"
    _interrupted_run(base)
    with fresh_folder(base) as folder:
        assert folder.path == base and folder.stale == LEFT
    live = tmp_path / "live"
    with OutFolder.open(live) as writer:  # a run still writing: its temporary file is no leftover
        tmp = writer.temp_path("samples.h5")
        with fresh_folder(live) as other:
            assert other.path == tmp_path / "live-2" and other.stale == ()
        assert tmp.exists()


def test_passing_over_a_folder_of_results_leaves_no_listing_open(tmp_path):
    """The default folder holding results (more than one entry: the check stops at the first) is passed over for
    ``base-2``, and the listing of ``base`` it read is closed, not left to the collector (no ResourceWarning)."""
    base = tmp_path / "press-hold"
    base.mkdir()
    for name in ("codes.npz", "record.json", "samples.h5"):
        (base / name).write_bytes(b"an earlier result")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ResourceWarning)
        with fresh_folder(base) as folder:
            assert folder.path == tmp_path / "press-hold-2"
        gc.collect()
    assert [str(w.message) for w in caught if issubclass(w.category, ResourceWarning)] == []


def test_the_write_probe_of_any_kind_of_folder_is_a_leftover(tmp_path):
    """A command killed while probing the folder leaves ``.probe.<random>.part``, whatever its kind of folder."""
    sweep = FolderKind("an earlier sweep's files", ("trials.csv",))
    out = tmp_path / "o"
    _interrupted_run(out, (".probe.k2j4_x9a.part", ".trials.csv.0a1b2c3d.part"))
    with OutFolder.open(out, kind=sweep) as folder:
        assert folder.stale == (".probe.k2j4_x9a.part", ".trials.csv.0a1b2c3d.part")


def test_the_temporary_names_the_bench_makes_are_the_ones_it_recognises(tmp_path):
    """Guards the name pattern against a change in how mkstemp names files."""
    made = [temp_path(tmp_path / name) for name in ("record.json", "samples.h5", "traces.png") for _ in range(20)]
    assert stale_temps(tmp_path) == sorted(p.name for p in made)
    for p in made:
        os.unlink(p)


def test_a_texture_sweep_into_a_folder_an_interrupted_sweep_left_says_so(tmp_path, monkeypatch, capsys):
    from bench.cli import main as cli
    from bench.experiments import trials as T
    from bench.tests.test_sweep_review import _in_process_sweep

    monkeypatch.setattr(T, "sweep", _in_process_sweep)
    out = tmp_path / "o"
    _interrupted_run(out, (".trials.csv.0a1b2c3d.part",))
    assert cli.main(["texture-sweep", "--textures", "902", "--movements", "21", "--trials", "1", "--quiet",
                     "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"note: --out {out}: removed 1 temporary file that an interrupted run left" in err, err
    assert ".trials.csv.0a1b2c3d.part" in err and not stale_temps(out) and (out / "trials.csv").exists()


def test_the_default_folder_s_note_says_no_out_was_given(tmp_path, monkeypatch, capsys):
    """Without --out the sweep chooses out/texture-sweep itself: its note about an interrupted sweep's leftovers
    names that folder as the default one (and how to choose another), never "--out" the user did not give."""
    from bench.cli import main as cli
    from bench.experiments import trials as T
    from bench.tests.test_sweep_review import _in_process_sweep

    monkeypatch.setattr(T, "sweep", _in_process_sweep)
    monkeypatch.chdir(tmp_path)
    _interrupted_run(tmp_path / "out" / "texture-sweep", (".trials.csv.0a1b2c3d.part",))
    assert cli.main(["texture-sweep", "--textures", "902", "--movements", "21", "--trials", "1", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert ("note: out/texture-sweep (the default folder; --out chooses another): removed 1 temporary file that an "
            "interrupted run left") in err and "--out out" not in err, err


def test_a_default_folder_refused_says_no_out_was_given(tmp_path):
    base = tmp_path / "press-hold"
    base.mkdir()
    (base / "notes.txt").write_text("mine")
    with pytest.raises(OutDirError) as e:
        fresh_folder(base, force=True)
    assert str(e.value).startswith(f"{base} (the default folder; --out chooses another): --force only replaces "), e
    assert (base / "notes.txt").read_text() == "mine"

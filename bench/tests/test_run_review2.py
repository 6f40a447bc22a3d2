"""Fixes from the second adversarial review: `run --force` removes nothing before the whole folder is checked; a
second Ctrl-C before the chunk ends still stops the exports; a several-sensor run writes every sensor under the
signal guard and the lock; only sensor2..sensor<MAX_SENSORS> folders are a run's own."""

import json
import os
import signal

import pytest

from bench.reporting import exports
from bench.reporting.outdir import LOCK_NAME, RUN, OutDirError, OutFolder
from bench.reporting.session import run_to_folder
from bench.scenes.scene import MAX_SENSORS, parse_scene
from bench.tests.cli_runs import run_cli
from bench.tests.test_outputs import check_consistent

PLOTS = ("traces.png", "spectrogram.png")


def _tree(folder) -> dict[str, str]:
    """Every file under ``folder`` (lock files aside) with its text."""
    return {p.relative_to(folder).as_posix(): p.read_text() for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name != LOCK_NAME}


def _earlier_several_sensor_run(out, sensors=(2, 3)) -> None:
    for folder in (out, *(out / f"sensor{k}" for k in sensors)):
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "record.json").write_text('{"status": "ok"}')
        (folder / "codes.npz").write_bytes(b"PK earlier")  # starts as an NPZ (a zip) does


# --- 1. --force checks the whole tree before it removes anything --------------------------------------------------
@pytest.mark.unit
def test_force_refuses_a_foreign_file_in_a_later_sensor_folder_and_removes_nothing(tmp_path):
    """A clean sensor2/ and a foreign file in sensor3/: refused, naming it, and sensor2/ and the top-level record
    are still there (they used to be removed before the refusal)."""
    out = tmp_path / "o"
    _earlier_several_sensor_run(out)
    (out / "sensor3" / "mine.txt").write_text("mine")
    before = _tree(out)
    with pytest.raises(OutDirError, match="sensor3/mine.txt"):
        OutFolder.open(out, force=True)
    assert _tree(out) == before


@pytest.mark.unit
def test_run_force_refuses_a_foreign_top_level_file_and_removes_no_sensor_folder(tmp_path):
    """The review's CLI case: notes.txt beside an earlier run with sensor2/ — exit 2, nothing removed."""
    out = tmp_path / "my out"
    _earlier_several_sensor_run(out, sensors=(2,))
    (out / "notes.txt").write_text("mine")
    before = _tree(out)
    r = run_cli("run", "taps", "--out", out, "--force", "--quiet", "--no-plots")
    assert r.returncode == 2 and "Traceback" not in r.stderr and "notes.txt" in r.stderr, r.stderr
    assert _tree(out) == before


@pytest.mark.unit
@pytest.mark.parametrize("foreign", ["sensor0", "sensor1", f"sensor{MAX_SENSORS + 1}", "sensor2/sensor3"])
def test_only_sensor2_to_max_sensors_folders_are_a_runs_own(tmp_path, foreign):
    """sensor0, sensor1, one past MAX_SENSORS, or a sensor folder nested in another: refused, nothing removed."""
    out = tmp_path / "o"
    _earlier_several_sensor_run(out, sensors=(2,))
    (out / foreign).mkdir(parents=True, exist_ok=True)
    (out / foreign / "record.json").write_text("{}")
    before = _tree(out)
    with pytest.raises(OutDirError, match=foreign.split("/")[-1]):
        OutFolder.open(out, force=True)
    assert _tree(out) == before
    assert RUN.subfolders == tuple(f"sensor{k}" for k in range(2, MAX_SENSORS + 1))


@pytest.mark.unit
def test_force_replaces_every_sensor_folder_of_an_earlier_run(tmp_path):
    out = tmp_path / "o"
    _earlier_several_sensor_run(out, sensors=range(2, MAX_SENSORS + 1))
    (out / "sensor2" / ".codes.npz.x1y2_3z4.part").write_text("left over")  # (mkstemp: 8 characters)
    OutFolder.open(out, force=True).close()
    assert [p.name for p in out.iterdir()] == [LOCK_NAME]


@pytest.mark.unit
def test_force_removes_each_folders_record_before_its_other_files(tmp_path, monkeypatch):
    """--force cut short (a signal, a file that cannot be removed) never leaves a record saying "ok" beside an
    earlier run's files half removed: the top-level record.json goes before anything, and in each sensor<k>/
    folder its record.json goes before that folder's other files (the module's docstring)."""
    out = tmp_path / "o"
    _earlier_several_sensor_run(out, sensors=(2, 3))  # codes.npz sorts before record.json in every folder
    removed = []
    unlink = os.unlink

    def note(path, *a, **k):
        rel = os.path.relpath(path, out)
        if not os.path.basename(rel).startswith("."):  # the write probe and the sensor folders' locks aside
            removed.append(rel)
        return unlink(path, *a, **k)

    monkeypatch.setattr(os, "unlink", note)
    OutFolder.open(out, force=True).close()
    monkeypatch.undo()
    assert [p.name for p in out.iterdir()] == [LOCK_NAME]
    assert sorted(removed) == sorted(["record.json", "codes.npz"] + [f"sensor{k}/{n}" for k in (2, 3)
                                                                      for n in ("record.json", "codes.npz")])
    assert removed[0] == "record.json"
    for k in (2, 3):
        assert [r for r in removed if r.startswith(f"sensor{k}/")][0] == f"sensor{k}/record.json", removed


# --- 2. a second signal before the chunk ends -----------------------------------------------------------------
@pytest.mark.unit
def test_two_signals_before_the_chunk_ends_stop_the_exports_and_plots(tmp_path, monkeypatch, capfd):
    """Both Ctrl-Cs arrive before the first chunk boundary: the simulation stops there, exports and plots are
    skipped (as the first signal's message promises), the record is still written, exit status 130."""
    from bench.reporting import session

    original = session.run_scene

    def run_scene(*args, should_stop, **kw):
        def stop_asked():
            if not sent:
                sent.append(1)
                os.kill(os.getpid(), signal.SIGINT)
                os.kill(os.getpid(), signal.SIGINT)
            return should_stop()

        sent = []
        return original(*args, should_stop=stop_asked, **kw)

    monkeypatch.setattr(session, "run_scene", run_scene)
    sc = parse_scene({"scene": {"name": "w", "duration_s": 3.0}})
    res = run_to_folder(sc, tmp_path / "o", csv=True, progress=False, chunk_s=0.5)
    err = capfd.readouterr().err
    assert "another signal stops the exports and plots" in err and "exports and plots will be skipped" in err
    assert res.exit_code == 130 and res.record["interrupted_by"] == "SIGINT"
    record = check_consistent(tmp_path / "o", "interrupted")
    assert record["simulated_s"] == 0.5
    assert set(record["skipped_outputs"]) == {"codes.npz", "samples.csv", *PLOTS}


# --- 3. several sensors: every sensor written under the guard, before sensor 1's record -----------------------
@pytest.mark.unit
def test_a_signal_while_sensor_2_is_written_still_writes_every_sensors_record(tmp_path, monkeypatch):
    """SIGINT while sensor 2's samples.csv is exported (the first export of a 3-sensor run): each sensor's
    record.json is written ("interrupted", its skipped outputs named), sensor 1's lists sensors 2 and 3."""
    original = exports.export_csv
    sent = []

    def signalled_csv(*args):
        if not sent:
            sent.append(1)
            os.kill(os.getpid(), signal.SIGINT)
        original(*args)

    monkeypatch.setattr(exports, "export_csv", signalled_csv)
    sc = parse_scene({"scene": {"name": "three", "duration_s": 0.5}, "sensors": [{"index": 2}, {"index": 3}]})
    out = tmp_path / "o"
    res = run_to_folder(sc, out, csv=True, progress=False, chunk_s=0.25)
    assert res.exit_code == 130
    sensor2 = json.loads((out / "sensor2" / "record.json").read_text())
    sensor3 = json.loads((out / "sensor3" / "record.json").read_text())
    assert sensor2["status"] == sensor3["status"] == "interrupted"
    assert "codes.npz" in sensor2["outputs"] and set(sensor2["skipped_outputs"]) == {"samples.csv", *PLOTS}
    assert set(sensor3["skipped_outputs"]) == {"codes.npz", "samples.csv", *PLOTS}
    record = check_consistent(out / "sensor2", "interrupted") and check_consistent(out, "interrupted")
    assert record["sensors"] == {  # each sensor's identity (unit, serial, twin_of) as its own record gives it
        f"sensor{k}": {"status": "interrupted", "error": None, "outputs": r["outputs"],
                       **{key: v for key, v in r["sensor"].items() if key not in ("index", "variant")}}
        for k, r in ((2, sensor2), (3, sensor3))}
    assert [sensor2["sensor"]["index"], sensor3["sensor"]["index"]] == [2, 3]
    assert len({sensor2["sensor"]["serial"], sensor3["sensor"]["serial"], record["sensor"]["serial"]}) == 3
    assert {k: (r["status"], r["outputs"]) for k, r in res.sensor_records.items()} == {
        2: ("interrupted", sensor2["outputs"]), 3: ("interrupted", sensor3["outputs"])}
    assert not [p for p in out.rglob("*.part")]


@pytest.mark.unit
def test_a_sensor_folder_that_cannot_be_written_fails_the_run(tmp_path, monkeypatch):
    """Sensor 3's folder refused (a writer holds its lock): sensors 1 and 2 written, the run "failed", naming it."""
    from bench.reporting import outdir

    sc = parse_scene({"scene": {"name": "three", "duration_s": 0.3}, "sensors": [{"index": 2}, {"index": 3}]})
    out = tmp_path / "o"
    original = outdir.OutFolder._prepare

    def prepare(self, force, keep=(), **kwargs):
        original(self, force, keep, **kwargs)
        if self.path == out:  # after the out folder is checked: another writer takes sensor3/
            (out / "sensor3").mkdir()
            held.append(outdir._lock(out / "sensor3", "x", "--out"))

    held = []
    monkeypatch.setattr(outdir.OutFolder, "_prepare", prepare)
    try:
        res = run_to_folder(sc, out, progress=False, plots=False)
    finally:
        for fd in held:
            os.close(fd)
    assert res.exit_code == 1
    record = check_consistent(out, "failed")
    assert record["sensors"]["sensor2"]["status"] == "ok" and record["sensors"]["sensor3"]["status"] == "failed"
    assert "sensor 3: OutDirError" in record["error"] and "sensor3/" in (out / "report.md").read_text()


# --- 4, 5, 7. record: a CSV beside --out that is not a recording is never removed; names in the CSV -------------
def _frames():
    import numpy as np

    from bench.hosts.driver import DataFrame

    ch = np.array([0, 17, 40])  # PAC, E1, E24 (a BioTac SP's)
    return [DataFrame(seq, 0b1, ch, np.array([[10 + seq], [20], [30]], np.uint16), np.zeros((3, 1), np.uint8))
            for seq in range(2)]


@pytest.mark.unit
@pytest.mark.parametrize("csv", [(), ("--csv",)], ids=["no csv", "csv"])
def test_record_force_refuses_a_csv_beside_out_that_is_not_a_recording(tmp_path, csv):
    """`record --out data.npz --force` used to delete the user's data.csv whatever it held: now refused before
    the port is opened (loop:// would be read), naming the file, and nothing is touched."""
    from bench.tests.cli_runs import run_cli

    (tmp_path / "data.csv").write_text("my own measurements\n")
    r = run_cli("record", "loop://", "--out", tmp_path / "data.npz", "--quiet", "--force", *csv)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert f"{tmp_path / 'data.csv'} is not a recording's CSV" in r.stderr
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == {"data.csv": "my own measurements\n"}


@pytest.mark.unit
def test_saving_a_recording_removes_only_a_recordings_csv_beside_it(tmp_path):
    from bench.cli.hosts import RECORDING_CSV_HEADER, _save_recording

    out, beside = tmp_path / "r.npz", tmp_path / "r.csv"
    beside.write_text(RECORDING_CSV_HEADER + "\n0,0,PAC,1,5,0\n")
    _save_recording(out, _frames(), {"end": "complete"}, csv=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.npz"]
    beside.write_text("seq,slot,channel\n")  # not a recording's (another header), e.g. written meanwhile
    _save_recording(out, _frames(), {"end": "complete"}, csv=False)
    assert beside.read_text() == "seq,slot,channel\n"


@pytest.mark.unit
def test_a_recordings_csv_names_the_channels_and_its_files_replace_symlinks(tmp_path):
    """The CSV's channel column holds names as run's samples.csv does (the NPZ keeps the indices); both files go
    in through outdir's temporary files, so a symbolic link at --out is replaced, never written through."""
    import numpy as np

    from bench.cli.hosts import RECORDING_CSV_HEADER, _save_recording

    target = tmp_path / "elsewhere.npz"
    target.write_text("not to be touched")
    out = tmp_path / "r.npz"
    out.symlink_to(target)
    written, not_written = _save_recording(out, _frames(), {"end": "complete"}, csv=True)
    assert written == [out, tmp_path / "r.csv"]
    assert target.read_text() == "not to be touched" and not out.is_symlink()
    assert np.load(out)["channels"][0].tolist() == [0, 17, 40]
    lines = (tmp_path / "r.csv").read_text().splitlines()
    assert lines[0] == RECORDING_CSV_HEADER
    assert lines[1:4] == ["0,0,PAC,1,10,0", "0,1,E1,1,20,0", "0,2,E24,1,30,0"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["elsewhere.npz", "r.csv", "r.npz"]  # no temporary file


# --- a signal after the record is written: the run is complete, and the exit says so -------------------------
@pytest.mark.unit
def test_a_signal_during_the_tidy_up_leaves_the_run_ok_and_exits_with_the_signal(tmp_path, monkeypatch):
    """SIGINT while the folder's temporaries are removed (record.json already "ok"): no KeyboardInterrupt escapes
    the guard, the lock is released, the record stays "ok", and the result carries the late signal (exit 130)."""
    from bench.reporting.outdir import OutFolder

    original = OutFolder.remove_temps

    def signalled_tidy_up(self):
        os.kill(os.getpid(), signal.SIGINT)
        original(self)

    monkeypatch.setattr(OutFolder, "remove_temps", signalled_tidy_up)
    sc = parse_scene({"scene": {"name": "w", "duration_s": 0.5}})
    try:
        res = run_to_folder(sc, tmp_path / "o", progress=False, plots=False)
    except KeyboardInterrupt:
        pytest.fail("the signal escaped the guard during the tidy-up")
    assert (res.record["status"], res.late_signal, res.exit_code) == ("ok", "SIGINT", 130)
    check_consistent(tmp_path / "o", "ok")
    OutFolder.open(tmp_path / "o", force=True).close()  # the lock was released: the folder opens again


@pytest.mark.unit
def test_run_says_the_files_are_complete_when_ctrl_c_cuts_only_the_summary(tmp_path, monkeypatch, capsys):
    """Ctrl-C while `run` prints report.md: exit 130 with a line saying the folder holds every file (status ok),
    not a bare "interrupted" that would send the user to re-run a finished scene."""
    from pathlib import Path

    from bench.cli.main import main

    original = Path.read_text

    def interrupted_read(self, *a, **kw):
        if self.name == "report.md":
            raise KeyboardInterrupt
        return original(self, *a, **kw)

    monkeypatch.setattr(Path, "read_text", interrupted_read)
    out = tmp_path / "o"
    assert main(["run", "rest", "--out", str(out), "--no-plots"]) == 130
    err = capsys.readouterr().err
    assert f"SIGINT after the run's files were written: {out}/ holds them all (record.json status \"ok\")" in err
    monkeypatch.setattr(Path, "read_text", original)
    check_consistent(out, "ok")


# --- "is this file ours?" never blocks on a FIFO, never follows a link (bench.atomic.open_regular) ------------
@pytest.mark.unit
def test_open_regular_opens_only_a_regular_file_and_never_blocks(tmp_path):
    from bench.atomic import open_regular, read_head

    (tmp_path / "f").write_bytes(b"# Scene report: x")
    os.mkfifo(tmp_path / "fifo")  # opened blocking, this waited for a writer for ever
    (tmp_path / "link").symlink_to(tmp_path / "f")
    (tmp_path / "dir").mkdir()

    def hung(signum, frame):
        raise TimeoutError("open_regular blocked on the FIFO")

    previous = signal.signal(signal.SIGALRM, hung)
    signal.alarm(10)  # a blocking open would wait for a writer for ever: fail instead
    try:
        assert open_regular(tmp_path / "fifo") is None
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    with open_regular(tmp_path / "f") as fh:
        assert fh.read() == b"# Scene report: x"
    assert [open_regular(tmp_path / n) for n in ("fifo", "link", "dir", "missing")] == [None] * 4
    assert (read_head(tmp_path / "f", 8), read_head(tmp_path / "fifo", 8)) == (b"# Scene ", None)


@pytest.mark.unit
def test_run_force_refuses_a_fifo_named_as_a_runs_file_at_once(tmp_path):
    """A FIFO named report.md in the folder hung `run --force` (it opened the pipe to read how it starts)."""
    out = tmp_path / "o"
    out.mkdir()
    os.mkfifo(out / "report.md")
    r = run_cli("run", "rest", "--out", out, "--force", "--quiet", "--no-plots", timeout=60)
    assert r.returncode == 2 and "report.md (not as this command writes it)" in r.stderr, r.stderr
    assert sorted(p.name for p in out.iterdir() if p.name != LOCK_NAME) == ["report.md"]


@pytest.mark.unit
@pytest.mark.parametrize("name", ["r.csv", "r.npz"])
def test_record_force_refuses_a_fifo_at_out_or_beside_it_at_once(tmp_path, name):
    os.mkfifo(tmp_path / name)
    r = run_cli("record", "loop://", "--out", tmp_path / "r.npz", "--quiet", "--force", "--csv", timeout=60)
    assert r.returncode == 2 and "Traceback" not in r.stderr and str(tmp_path / name) in r.stderr, r.stderr
    assert [p.name for p in tmp_path.iterdir()] == [name]


# --- a full disk while a recording is saved: nothing of the stream is lost -------------------------------------------
@pytest.mark.unit
def test_a_csv_that_does_not_fit_leaves_the_npz_placed_and_says_so(tmp_path, monkeypatch):
    """ENOSPC while the CSV is written: the NPZ (every sample) is still put in place, the CSV is named as not
    written with the reason, and no temporary file is left."""
    import errno

    from bench import atomic
    from bench.cli import hosts

    original = atomic.written_temp

    def full_for_csv(final, write):
        if final.suffix == ".csv":
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return original(final, write)

    monkeypatch.setattr(atomic, "written_temp", full_for_csv)
    written, not_written = hosts._save_recording(tmp_path / "r.npz", _frames(), {"end": "complete"}, csv=True)
    assert written == [tmp_path / "r.npz"] and not_written == {tmp_path / "r.csv": os.strerror(errno.ENOSPC)}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.npz"]


@pytest.mark.unit
def test_an_npz_that_cannot_be_written_is_saved_in_the_temporary_folder_and_named(tmp_path, monkeypatch):
    """ENOSPC at --out: the recording goes to the system's temporary folder, the error names that file (a live stream
    cannot be recorded again), and nothing is left at --out."""
    import errno
    import tempfile

    import numpy as np

    from bench import atomic
    from bench.cli import hosts
    from bench.errors import OutputNotWritten

    out_disk, spare = tmp_path / "full", tmp_path / "spare"
    spare.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(spare))
    original = atomic.written_temp

    def full_disk(final, write):
        if final.parent == out_disk:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return original(final, write)

    monkeypatch.setattr(atomic, "written_temp", full_disk)
    with pytest.raises(OutputNotWritten) as e:
        hosts._save_recording(out_disk / "r.npz", _frames(), {"end": "complete"}, csv=True)
    rescued = list(spare.iterdir())
    assert len(rescued) == 1 and f"it was saved as {rescued[0]} instead" in str(e.value)
    assert "No space left on device" in str(e.value) and list(out_disk.iterdir()) == []
    assert np.load(rescued[0])["codes"].tolist() == [[[10], [20], [30]], [[11], [20], [30]]]


@pytest.mark.unit
def test_a_run_whose_record_cannot_be_written_says_the_folder_is_incomplete(tmp_path, monkeypatch, capsys):
    """ENOSPC on record.json (the last file written): exit 1 with one line naming record.json and the folder, and
    report.md and samples.h5, already in place, no longer say "ok"."""
    import errno

    import h5py

    from bench.cli.main import main
    from bench.reporting.outdir import OutFolder

    original = OutFolder.write_text

    def full_for_the_record(self, name, text):
        if name == "record.json":
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return original(self, name, text)

    monkeypatch.setattr(OutFolder, "write_text", full_for_the_record)
    out = tmp_path / "o"
    assert main(["run", "rest", "--out", str(out), "--no-plots", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert f"error: {out}/record.json could not be written (No space left on device)" in err, err
    assert "Traceback" not in err and not (out / "record.json").exists()
    assert "failed" in (out / "report.md").read_text()
    with h5py.File(out / "samples.h5") as f:
        assert f.attrs["status"] == "failed"



# --- a part the same Ctrl-C reached fails as it ends: the run was interrupted, not failed ---------------------------
@pytest.mark.unit
def test_a_build_killed_by_the_same_ctrl_c_is_an_interruption(tmp_path, monkeypatch, capsys):
    """A first `run --spi rtl` compiles the RTL; Ctrl-C reaches the compilers too, which die, and the build raises.
    The run is "interrupted" (exit 130, one line), not "failed" with the compilers' dying words."""
    from bench.cli.main import main
    from bench.errors import BuildError
    from bench.running import runner

    def build_dies_of_the_ctrl_c(scene, sensor):
        os.kill(os.getpid(), signal.SIGINT)  # the terminal's Ctrl-C, to the whole process group
        raise BuildError("RTL harness does not compile:\n%Error: Verilator threw signal 2\nmake: *** Interrupt")

    monkeypatch.setattr(runner, "peripheral_for", build_dies_of_the_ctrl_c)
    out = tmp_path / "o"
    assert main(["run", "rest", "--out", str(out), "--quiet", "--no-plots"]) == 130
    err = capsys.readouterr().err
    assert "Verilator" not in err and "interrupted by SIGINT at 0.000 s" in err, err
    record = check_consistent(out, "interrupted")
    assert "does not compile" in record["error"]  # the build's last words are kept in the record


@pytest.mark.unit
def test_any_other_failure_after_a_signal_is_still_a_failure(tmp_path, monkeypatch, capsys):
    """Only a build the signal reached is taken for the interruption: an I/O error after a Ctrl-C is a failure,
    its error said."""
    from bench.cli.main import main
    from bench.running import runner

    def fails_after_a_signal(scene, sensor):
        os.kill(os.getpid(), signal.SIGINT)
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(runner, "peripheral_for", fails_after_a_signal)
    out = tmp_path / "o"
    assert main(["run", "rest", "--out", str(out), "--quiet", "--no-plots"]) == 1
    assert "Input/output error" in capsys.readouterr().err
    assert "Input/output error" in check_consistent(out, "failed")["error"]


@pytest.mark.unit
def test_a_signal_inherited_as_ignored_is_not_re_raised_over_a_later_sigterm():
    """A process started with SIGINT ignored gets INT, INT, TERM inside signals_held: SIGINT stays ignored (nothing
    to note), and the SIGTERM is the one delivered after the block — the process ends by it, not with status 0."""
    import subprocess
    import sys

    code = ("import os, signal, time\n"
            "from bench.campaigns.engine import signals_held\n"
            "with signals_held():\n"
            "    for s in (signal.SIGINT, signal.SIGINT, signal.SIGTERM):\n"
            "        os.kill(os.getpid(), s)\n"
            "    time.sleep(0.2)\n"
            "print('survived')\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                       preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN))
    assert r.returncode == -signal.SIGTERM and "survived" not in r.stdout, (r.returncode, r.stdout, r.stderr)


# --- a first `run --spi rtl` builds the RTL: said on the bar, and no part of the run's speed ------------------------
@pytest.mark.rtl
def test_a_first_rtl_run_says_it_is_building_and_keeps_the_build_out_of_its_wall_time(tmp_path, monkeypatch, capsys):
    """The first `run --spi rtl` (or the first after the RTL changed) compiles the harness with Verilator, a minute
    or more: the progress bar says so meanwhile (it had sat at 0 % without a word), and the run's wall time — its
    report's "× real time" — starts after the build (a 6 s scene had said 0.14× real time, 3.7× when run again). The
    harness is really built, into a folder of this test's own."""
    import time

    from emulator.rtl import harness
    from bench.running.runner import run_scene
    from bench.scenes.scene import parse_scene_text

    monkeypatch.setattr(harness, "DEFAULT_DIR", tmp_path / "rtl_harness")  # a fresh build, not the shared one
    build = harness.Harness._build
    built_s = []

    def timed_build(self):  # the real build, its duration noted (a few s with a warm compiler cache, a minute cold)
        t = time.perf_counter()
        try:
            return build(self)
        finally:
            built_s.append(time.perf_counter() - t)

    monkeypatch.setattr(harness.Harness, "_build", timed_build)
    scene = parse_scene_text('[scene]\nname = "first-rtl"\nduration_s = 0.3\nseed = 1\nfidelity = "fast"\n'
                        '[host]\nspi = "rtl"\nsequence = ["PAC", "PDC"]\n')
    t0 = time.perf_counter()
    rec = run_scene(scene, progress=True)
    whole_s = time.perf_counter() - t0
    assert rec.error is None and rec.status == "ok", rec.error
    assert (tmp_path / "rtl_harness" / "harness").is_file()  # built here, by this run
    assert "first-rtl: building the RTL harness with Verilator" in capsys.readouterr().err
    assert len(built_s) == 1 and rec.wall_s <= whole_s - built_s[0], (rec.wall_s, whole_s, built_s)

"""Runs that lose nothing: the out folder is checked before anything runs, locked, written atomically; SIGINT and
SIGTERM keep what was recorded; samples stream to samples.h5 with flat memory; every failure writes the record.

The interruption and concurrency loops run a few rounds in the suite; ``BIOTAC_OUTPUT_STRESS=1`` runs the issue's
full figures (20 interrupted runs, 10 concurrent pairs)."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from bench.cli import main as cli
from bench.reporting import store
from bench.reporting.outdir import LOCK_NAME, OutDirError, OutFolder
from bench.reporting.report import write_outputs
from bench.running.aggregate import ENVELOPE_BINS, SPECTROGRAM_COLUMNS, RunSummary
from bench.running.runner import make_chunk, run_scene
from bench.running.sampler import Sampler
from bench.scenes.scene import parse_scene

REPO = Path(__file__).resolve().parents[2]
STRESS = bool(os.environ.get("BIOTAC_OUTPUT_STRESS"))


def _scene_file(tmp_path: Path, duration_s: float, name: str = "t", extra: str = "") -> Path:
    f = tmp_path / f"{name}_{duration_s:g}.toml"
    f.write_text(f'[scene]\nname = "{name}"\nduration_s = {float(duration_s)!r}\nseed = 3\n'
                 f'[host]\nsequence = "default"\n{extra}')
    return f


def _bench(*args, **kw):
    return subprocess.Popen([sys.executable, "-m", "bench.cli", *map(str, args)], cwd=REPO, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)


def _visible(folder: Path) -> set[str]:
    return {p.name for p in folder.iterdir() if p.name != LOCK_NAME}


def check_consistent(folder: Path, status: str | None = None) -> dict:
    """A finished out folder is consistent: record.json present, every output it lists present and no other
    file (but the sensor folders it lists), no temporary file, samples.h5 with the record's status and exactly the samples of ``simulated_s``,
    codes.npz (when written) equal to samples.h5 bit for bit."""
    record = json.loads((folder / "record.json").read_text())
    names = _visible(folder) - set(record.get("sensors", {}))  # a several-sensor run's sensor<k>/ folders
    assert set(record["outputs"]) == names, (record["outputs"], names)
    if status:
        assert record["status"] == status, record
    h5 = folder / "samples.h5"
    attrs = store.read_attrs(h5)
    assert attrs["status"] == record["status"] and attrs["simulated_s"] == record["simulated_s"]
    # the file describes its run as the record does: the sequence as JSON, the bus's rates, the stop's signal
    assert json.loads(attrs["sequence"]) == record["host"]["sequence"]
    assert (attrs["slot_rate_Hz"], attrs["spi_clock_Hz"]) == (record["host"]["slot_rate_Hz"],
                                                              record["host"]["spi_clock_Hz"])
    assert attrs.get("interrupted_by", "") == record.get("interrupted_by", "")
    sc = parse_scene({"scene": {"name": "x", "duration_s": 1.0}, "host": {"sequence": record["host"]["sequence"],
                                                                         "slot_rate_Hz": record["host"]["slot_rate_Hz"]}})
    slots = int(round(record["simulated_s"] * sc.slot_rate_Hz))
    sampler = Sampler(None, sc.sequence, sc.slot_rate_Hz, sc.spi_clock_Hz)
    _, t_expected, ch_expected = sampler.slots(np.arange(slots))
    channels = store.read_channels(h5)
    from emulator.channels import CHANNEL_INDEX

    for name, r in channels.items():
        want = t_expected[ch_expected == CHANNEL_INDEX[name]]
        assert r.times.size == want.size == record["channels"][name]["samples"], name
        assert np.array_equal(r.times, want), name
    if "codes.npz" in names:
        data = np.load(folder / "codes.npz")
        for name, r in channels.items():
            for key, a in (("t", r.times), ("code", r.codes), ("status", r.status)):
                b = data[f"{name}_{key}"]
                assert b.dtype == a.dtype and np.array_equal(a, b), (name, key)
        assert str(data["scene_toml"]) == attrs["scene_toml"]
    return record


# ---------------------------------------------------------------------------------------------- out folder
@pytest.mark.unit
def test_a_file_as_out_is_refused_before_anything_runs(tmp_path):
    f = tmp_path / "afile"
    f.write_text("mine")
    t0 = time.perf_counter()
    p = _bench("run", _scene_file(tmp_path, 36000.0), "--out", f, "--quiet")
    out, err = p.communicate(timeout=120)
    assert p.returncode == 2, err
    assert f"--out {f}: " in err and "is a file" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert time.perf_counter() - t0 < 60  # ten simulated hours did not run first
    assert f.read_text() == "mine"


@pytest.mark.unit
def test_out_under_a_file_is_refused(tmp_path, capsys):
    f = tmp_path / "afile"
    f.write_text("x")
    assert cli.main(["run", str(_scene_file(tmp_path, 1.0)), "--out", str(f / "sub"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "a part of the path is a file" in err


@pytest.mark.unit
def test_a_nul_byte_in_out_is_refused(tmp_path, capsys):
    assert cli.main(["run", str(_scene_file(tmp_path, 1.0)), "--out", str(tmp_path / "a\x00b"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "NUL byte" in err and "Traceback" not in err


@pytest.mark.unit
def test_an_unwritable_out_is_refused(tmp_path, capsys):
    if os.geteuid() == 0:  # root writes anywhere a mode allows nothing: use a read-only file system instead
        target = Path("/proc/biotac-bench-out")
    else:
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        target = ro / "out"
    assert cli.main(["run", str(_scene_file(tmp_path, 1.0)), "--out", str(target), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"--out {target}: " in err and ("cannot create" in err or "not writable" in err)


@pytest.mark.unit
def test_a_non_empty_out_is_refused_without_force_and_force_replaces_the_earlier_run(tmp_path, capsys):
    scene = str(_scene_file(tmp_path, 1.0))
    out = tmp_path / "out"
    assert cli.main(["run", scene, "--out", str(out), "--quiet", "--csv", "--seed", "5"]) == 0
    first = check_consistent(out, "ok")
    assert "samples.csv" in first["outputs"]
    capsys.readouterr()
    assert cli.main(["run", scene, "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "not empty" in err and "--force" in err and f"--out {out}: " in err
    assert json.loads((out / "record.json").read_text()) == first  # untouched
    assert cli.main(["run", scene, "--out", str(out), "--quiet", "--force", "--no-plots", "--seed", "6"]) == 0
    second = check_consistent(out, "ok")
    assert "samples.csv" not in _visible(out) and "traces.png" not in _visible(out)  # nothing of the first run
    assert second["scene"]["seed"] == 6 and store.read_attrs(out / "samples.h5")["seed"] == 6


@pytest.mark.unit
def test_force_never_removes_files_that_are_not_a_runs_own(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "thesis.tex").write_text("precious")
    (out / "record.json").write_text("{}")
    assert cli.main(["run", str(_scene_file(tmp_path, 1.0)), "--out", str(out), "--quiet", "--force"]) == 2
    assert "thesis.tex" in capsys.readouterr().err
    assert (out / "thesis.tex").read_text() == "precious" and (out / "record.json").read_text() == "{}"


@pytest.mark.unit
@pytest.mark.parametrize("name, own", [("samples.h5", b"\x89HDF\r\n\x1a\n rest of an HDF5 file"),
                                       ("codes.npz", b"PK\x03\x04 rest of a zip"),
                                       ("record.json", b'{"status": "ok"}')])
def test_force_tells_the_binary_and_json_outputs_from_a_users_files_of_that_name(tmp_path, name, own):
    """README: --force recognises a run's file by how it starts — the HDF5, NPZ (zip) and JSON signatures as well as
    the report's and CSV's: a user's file of that name starting otherwise is refused and kept, one that starts as a
    run's is removed."""
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / name).write_bytes(b"my own data, not a run's")
    with pytest.raises(OutDirError, match=rf"{name} \(not as this command writes it\)"):
        OutFolder.open(theirs, force=True)
    assert (theirs / name).read_bytes() == b"my own data, not a run's"
    earlier = tmp_path / "earlier"
    earlier.mkdir()
    (earlier / name).write_bytes(own)
    OutFolder.open(earlier, force=True).close()
    assert not (earlier / name).exists()


def test_force_never_removes_a_file_named_as_a_runs_that_the_run_did_not_write(tmp_path, capsys):
    """Found by a hostile pass: --force matched by name only and removed the user's own report.md and samples.csv.
    Each of a run's files is recognised by how it starts (the report's heading, the CSV's header, HDF5, NPZ and PNG
    signatures, JSON); an earlier run's own files are still replaced."""
    scene = str(_scene_file(tmp_path, 1.0))
    for name, text in (("report.md", "my notes on the rig"), ("samples.csv", "a,b\n1,2\n"),
                       ("traces.png", "not a picture")):
        out = tmp_path / name.replace(".", "_")
        out.mkdir()
        (out / name).write_text(text)
        assert cli.main(["run", scene, "--out", str(out), "--quiet", "--force"]) == 2
        assert f"{name} (not as this command writes it)" in capsys.readouterr().err
        assert (out / name).read_text() == text and [p.name for p in out.iterdir() if p.name != LOCK_NAME] == [name]
    out = tmp_path / "earlier"
    assert cli.main(["run", scene, "--out", str(out), "--quiet", "--csv"]) == 0
    assert cli.main(["run", scene, "--out", str(out), "--quiet", "--force"]) == 0
    check_consistent(out, "ok")


@pytest.mark.unit
def test_symlinks_in_the_out_folder_are_replaced_not_followed(tmp_path):
    out, outside = tmp_path / "out", tmp_path / "outside.txt"
    out.mkdir()
    outside.write_text("keep me")
    (out / "record.json").symlink_to(outside)
    (out / "traces.png").symlink_to(outside)
    assert cli.main(["run", str(_scene_file(tmp_path, 1.0)), "--out", str(out), "--quiet", "--force"]) == 0
    assert outside.read_text() == "keep me"
    assert not (out / "record.json").is_symlink() and not (out / "traces.png").is_symlink()
    check_consistent(out, "ok")


@pytest.mark.unit
def test_a_symlinked_lock_file_is_refused(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / LOCK_NAME).symlink_to(tmp_path / "elsewhere")
    with pytest.raises(OutDirError, match="symbolic link"):
        OutFolder.open(out)
    assert not (tmp_path / "elsewhere").exists()


@pytest.mark.unit
def test_the_lock_refuses_a_second_writer_at_once(tmp_path):
    with OutFolder.open(tmp_path / "o"):
        t0 = time.perf_counter()
        with pytest.raises(OutDirError, match=rf"another run \(pid {os.getpid()}\) is writing into this folder"):
            OutFolder.open(tmp_path / "o", force=True)
        assert time.perf_counter() - t0 < 1.0
    OutFolder.open(tmp_path / "o").close()  # released


@pytest.mark.unit
def test_the_lock_names_its_holder_after_a_longer_pid_held_it(tmp_path):
    """The lock file stays after a run, holding that run's pid (the module's docstring); the next run's pid
    replaces it whole, so a second writer is refused naming the run that holds the folder now, not a mix of both."""
    out = tmp_path / "o"
    out.mkdir()
    (out / LOCK_NAME).write_text("4194304999\n")  # an earlier holder's, longer than any pid of this run
    with OutFolder.open(out):
        assert (out / LOCK_NAME).read_text() == f"{os.getpid()}\n"
        with pytest.raises(OutDirError, match=rf"another run \(pid {os.getpid()}\) is writing into this folder"):
            OutFolder.open(out, force=True)


@pytest.mark.unit
def test_the_files_are_put_in_place_in_the_documented_order(tmp_path, monkeypatch):
    """README: every file is written under a temporary name and renamed into place in the order exports, plots,
    samples.h5, report.md, record.json — so a record.json means every file it lists is complete."""
    import bench.atomic as atomic
    from bench.reporting.session import run_to_folder

    placed = []
    real = atomic.commit
    import bench.reporting.outdir as outdir

    def spy(tmp, final):
        if not Path(final).name.startswith("."):  # a plot saved under its temporary name first
            placed.append(Path(final).name)
        return real(tmp, final)

    monkeypatch.setattr(atomic, "commit", spy)
    monkeypatch.setattr(outdir, "commit", spy)
    sc = parse_scene({"scene": {"name": "order", "duration_s": 2.5},
                      "stimulus": [{"kind": "touch", "electrode": "E7", "start_s": 0.2, "force_N": 1.0}]})
    res = run_to_folder(sc, tmp_path / "o", csv=True, progress=False)
    assert res.exit_code == 0 and sorted(placed) == sorted(res.record["outputs"]), placed
    plots = [n for n in placed if n.endswith(".png")]
    assert "electrode_map.png" in plots
    assert placed == ["codes.npz", "samples.csv", *plots, "samples.h5", "report.md", "record.json"], placed


@pytest.mark.unit
def test_a_signal_stops_the_run_at_the_end_of_its_4_s_chunk(tmp_path, monkeypatch):
    """README: SIGTERM stops the run at the next chunk (4 simulated s) and writes what was recorded, status
    "interrupted", exit status 143. The signal arrives while the first chunk is stored: exactly 4 s are kept."""
    from bench.reporting.session import run_to_folder

    real_add, sent = store.SampleStore.add, []

    def add(self, parts):
        if not sent:
            sent.append(os.kill(os.getpid(), signal.SIGTERM))
        return real_add(self, parts)

    monkeypatch.setattr(store.SampleStore, "add", add)
    sc = parse_scene({"scene": {"name": "chunks", "duration_s": 12.0}, "host": {"sequence": ["PAC"],
                                                                               "slot_rate_Hz": 2200.0}})
    res = run_to_folder(sc, tmp_path / "o", plots=False, progress=False)
    assert (res.exit_code, res.record["status"], res.record["simulated_s"]) == (143, "interrupted", 4.0)
    assert res.record["channels"]["PAC"]["samples"] == 4 * 2200


@pytest.mark.unit
def test_without_out_each_run_gets_a_fresh_folder(tmp_path):
    from bench.reporting.session import run_to_folder

    sc = parse_scene({"scene": {"name": "fresh", "duration_s": 0.2}, "host": {"sequence": ["PAC"],
                                                                             "slot_rate_Hz": 2200.0}})
    a = run_to_folder(sc, None, plots=False, progress=False, out_root=tmp_path)
    b = run_to_folder(sc, None, plots=False, progress=False, out_root=tmp_path)
    assert (a.folder.name, b.folder.name) == ("fresh", "fresh-2") and a.exit_code == b.exit_code == 0


@pytest.mark.unit
def test_a_default_folder_that_another_run_holds_is_passed_over(tmp_path):
    """Without --out, a run whose default folder is still empty but locked by another run (which has not written a
    file yet) takes the next free one, ``<name>-2``: neither refused nor writing into the other run's folder."""
    from bench.reporting.outdir import fresh_folder

    with OutFolder.open(tmp_path / "fresh"):
        with fresh_folder(tmp_path / "fresh") as second:
            assert second.path == tmp_path / "fresh-2"


@pytest.mark.unit
def test_the_default_folders_count_on_past_two(tmp_path):
    """README: without --out, `out/<scene name>`, then `-2`, `-3`, …: with the first two holding earlier runs' files,
    the third run gets `<name>-3` (and a fourth `<name>-4`), not a refusal or one of the earlier folders."""
    from bench.reporting.outdir import fresh_folder

    for name in ("fresh", "fresh-2"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "record.json").write_text("{}")
    with fresh_folder(tmp_path / "fresh") as third:
        assert third.path == tmp_path / "fresh-3"
        (third.path / "record.json").write_text("{}")
    with fresh_folder(tmp_path / "fresh") as fourth:
        assert fourth.path == tmp_path / "fresh-4"


@pytest.mark.unit
def test_a_scene_name_that_is_a_path_is_rejected(tmp_path, capsys):
    f = tmp_path / "evil.toml"
    f.write_text('[scene]\nname = "../../x"\nduration_s = 1.0\n')
    assert cli.main(["run", str(f), "--quiet"]) == 2
    assert 'scene.name = "../../x"' in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------- contents
@pytest.mark.unit
def test_samples_h5_equals_the_npz_export_and_the_in_memory_run_bit_for_bit(tmp_path):
    sc = parse_scene({"scene": {"name": "eq", "duration_s": 2.0, "seed": 9},
                      "stimulus": [{"kind": "tap", "at_s": [0.5, 1.5], "peak_N": 0.5}]})
    out = tmp_path / "o"
    assert cli.main(["run", str(_scene_file(tmp_path, 2.0, "eq", '[[stimulus]]\nkind = "tap"\nat_s = [0.5, 1.5]\n'
                                                          'peak_N = 0.5\n').as_posix()),
                     "--out", str(out), "--quiet", "--seed", "9"]) == 0
    record = check_consistent(out, "ok")
    mem = run_scene(sc, progress=False)
    h5 = store.read_channels(out / "samples.h5")
    assert list(h5) == list(mem.channels)
    for name, r in mem.channels.items():
        for a, b in ((r.times, h5[name].times), (r.codes, h5[name].codes), (r.status, h5[name].status)):
            assert a.dtype == b.dtype and np.array_equal(a, b), name
    with h5py.File(out / "samples.h5") as f:
        assert f["PAC/t"].attrs["units"] == "s" and f["PAC/code"].dtype == np.uint16
        assert f["PAC/code"].chunks and f["PAC/code"].maxshape == (None,)
        assert f.attrs["seed"] == 9 and f.attrs["fidelity"] == "default" and "[[stimulus]]" in f.attrs["scene_toml"]
    assert record["channels"]["PAC"]["samples"] == mem.channels["PAC"].codes.size


@pytest.mark.unit
def test_long_runs_keep_no_samples_in_memory_and_say_why_exports_were_skipped(tmp_path, monkeypatch):
    from bench.reporting import exports
    from bench.running import runner

    monkeypatch.setattr(exports, "EXPORT_MAX_S", 0.5)
    monkeypatch.setattr(runner, "KEEP_SAMPLES_MAX_S", 0.5)
    sc = parse_scene({"scene": {"name": "long", "duration_s": 1.0}, "host": {"sequence": ["PAC", "PDC"],
                                                                            "slot_rate_Hz": 2200.0}})
    rec = run_scene(sc, progress=False)
    assert dict(rec.channels) == {} and rec.summary.channels["PAC"].samples == 1100
    from bench.reporting.session import run_to_folder

    res = run_to_folder(sc, tmp_path / "o", csv=True, plots=False, progress=False)
    assert "codes.npz" not in res.record["outputs"] and "--npz" in res.record["skipped_outputs"]["codes.npz"]
    assert "--npz" in (tmp_path / "o" / "report.md").read_text()
    assert res.recording.channels["PAC"].codes.size == 1100  # read back from samples.h5 on demand
    forced = run_to_folder(sc, tmp_path / "f", csv=True, npz=True, plots=False, progress=False)
    assert {"codes.npz", "samples.csv"} <= set(forced.record["outputs"])
    check_consistent(tmp_path / "f", "ok")


@pytest.mark.unit
@pytest.mark.parametrize("duration_s, exported", [(600.0, True), (601.0, False)])
def test_exports_and_samples_in_memory_stop_past_600_simulated_s(tmp_path, duration_s, exported):
    """README: the exports are written for runs up to 600 simulated s, and `run_scene` keeps every sample in
    `Recording.channels` for scenes up to 600 s; a longer run keeps only samples.h5 and says so. Checked on each side
    of the limit (PDC alone at 100 slots/s keeps it fast)."""
    from bench.reporting.session import run_to_folder

    sc = parse_scene({"scene": {"name": "edge", "duration_s": duration_s},
                      "host": {"sequence": ["PDC"], "slot_rate_Hz": 100.0}})
    assert bool(run_scene(sc, progress=False).channels) is exported
    res = run_to_folder(sc, tmp_path / "o", plots=False, progress=False)
    assert ("codes.npz" in res.record["outputs"]) is exported
    assert ("codes.npz" in res.record.get("skipped_outputs", {})) is not exported


@pytest.mark.unit
def test_the_summary_is_bounded_whatever_the_duration():
    """Feeding ten hours of a full frame's worth of chunks keeps plot data at a fixed size."""
    sc = parse_scene({"scene": {"name": "s", "duration_s": 36000.0}, "host": {"sequence": ["PAC"],
                                                                             "slot_rate_Hz": 2200.0}})
    s = RunSummary(sc, ["PAC"])
    rng = np.random.default_rng(0)
    for k in range(0, 36000, 60):  # one chunk per simulated minute
        t = k + np.arange(132000) / 2200.0
        s.add(make_chunk({"PAC": (t, rng.integers(2040, 2056, t.size).astype(np.uint16), np.zeros(t.size, np.uint8))}))
    s.finish()
    f, tt, sxx = s.spectrogram.result()
    assert SPECTROGRAM_COLUMNS == ENVELOPE_BINS == 1000  # README: 1000 envelope bins, at most 1000 columns
    assert sxx.shape[1] <= SPECTROGRAM_COLUMNS and s.env_n.shape == (1, ENVELOPE_BINS)
    assert s.channels["PAC"].samples == 36000 * 2200 and tt[-1] > 35900


@pytest.mark.unit
@pytest.mark.parametrize("stimuli, block_s", [([], 0.137), ([{"kind": "touch", "start_s": 0.3, "force_N": 1.0,
                                                               "ramp_s": 0.05, "hold_s": 1.5, "electrode": "E17",
                                                               "material": "aluminum"}], 0.0137)])
def test_csv_export_is_the_same_whatever_its_time_blocks(tmp_path, stimuli, block_s):
    """At rest, and while a touch on aluminum moves TDC (so the TDC a TAC sample is converted with — between the
    TDC samples around it, the next one perhaps in the next block — matters), the CSV written in blocks of
    ``block_s`` is the one written in one block, byte for byte."""
    from bench.reporting import exports

    sc = parse_scene({"scene": {"name": "csv", "duration_s": 2.0}, "stimulus": stimuli})
    rec = run_scene(sc, progress=False)
    write_outputs(rec, tmp_path / "a", plots=False)
    base = {"PAC": 2048.0, "PDC": 700.0, "TAC": 2048.0}
    exports.export_csv(tmp_path / "a" / "samples.h5", tmp_path / "one.csv", base, block_s=60.0)
    exports.export_csv(tmp_path / "a" / "samples.h5", tmp_path / "many.csv", base, block_s=block_s)
    one, many = (tmp_path / "one.csv").read_text(), (tmp_path / "many.csv").read_text()
    assert one == many and one.count("\n") == 1 + 2.0 * 4400
    assert ",TAC," in one and "degC/s" in one


# ---------------------------------------------------------------------------------------------- failures
@pytest.mark.unit
def test_a_nan_mid_run_writes_the_record_as_failed(tmp_path, monkeypatch, capsys):
    from emulator.transducer import Bridge

    original = Bridge.process

    def poisoned(self, block, inputs):
        out = original(self, block, inputs)
        if block.times[-1] > 5.5:
            for v in out.values():
                v[block.times > 5.5] = np.nan
        return out

    monkeypatch.setattr(Bridge, "process", poisoned)
    out = tmp_path / "o"
    assert cli.main(["run", str(_scene_file(tmp_path, 10.0)), "--out", str(out), "--quiet"]) == 1
    record = check_consistent(out, "failed")
    assert "NumericalError" in record["error"] and "non-finite" in record["error"]
    assert 0 < record["simulated_s"] <= 5.5  # everything up to the chunk that failed is kept
    assert "error: the run failed at " in capsys.readouterr().err


@pytest.mark.unit
def test_an_error_while_writing_writes_the_record_as_failed(tmp_path, monkeypatch):
    from bench.reporting import plots

    def broken(rec, base):
        def draw(path):
            path.write_bytes(b"half a png")
            raise MemoryError("no room for the figure")
        return [("traces.png", draw)]

    monkeypatch.setattr(plots, "scene_plots", broken)
    out = tmp_path / "o"
    assert cli.main(["run", str(_scene_file(tmp_path, 0.5)), "--out", str(out), "--quiet"]) == 1
    record = check_consistent(out, "failed")
    assert "writing traces.png: MemoryError" in record["error"] and "traces.png" not in _visible(out)


@pytest.mark.unit
def test_a_report_that_cannot_be_written_is_not_listed_as_an_output(tmp_path, monkeypatch):
    """report.md fails to write (a full disk, say): record.json says "failed", names report.md in its error and does
    not list it among its outputs — every file the record lists is there (check_consistent), as the README promises
    of a present record.json."""
    real = OutFolder.write_text

    def no_report(self, name, text):
        if name == "report.md":
            raise OSError(28, "No space left on device")
        return real(self, name, text)

    monkeypatch.setattr(OutFolder, "write_text", no_report)
    out = tmp_path / "o"
    assert cli.main(["run", str(_scene_file(tmp_path, 0.5)), "--out", str(out), "--quiet", "--no-plots"]) == 1
    record = check_consistent(out, "failed")
    assert "writing report.md: OSError" in record["error"] and "report.md" not in record["outputs"]


@pytest.mark.unit
def test_a_record_that_cannot_be_built_is_still_written(tmp_path, monkeypatch):
    from bench.reporting import report

    def broken(*a, **kw):
        raise KeyError("impact_detection")

    monkeypatch.setattr(report, "build_record", broken)
    out = tmp_path / "o"
    assert cli.main(["run", str(_scene_file(tmp_path, 0.5)), "--out", str(out), "--quiet", "--no-plots"]) == 1
    record = json.loads((out / "record.json").read_text())
    assert record["status"] == "failed" and "building the record: KeyError" in record["error"]
    assert store.read_attrs(out / "samples.h5")["status"] == "failed"


@pytest.mark.unit
def test_signals_while_writing_stop_the_exports_and_still_write_the_record(tmp_path, monkeypatch):
    """Two SIGINTs arrive while codes.npz is being written: no half-written file, record says interrupted."""
    from bench.reporting import exports
    from bench.reporting.session import run_to_folder

    original = exports.export_npz

    def interrupted_twice(h5, dest, base, checkpoint):
        def cp():
            os.kill(os.getpid(), signal.SIGINT)
            os.kill(os.getpid(), signal.SIGINT)
            checkpoint()
        original(h5, dest, base, cp)

    monkeypatch.setattr(exports, "export_npz", interrupted_twice)
    sc = parse_scene({"scene": {"name": "w", "duration_s": 0.5}})
    res = run_to_folder(sc, tmp_path / "o", csv=True, progress=False)
    assert res.exit_code == 130 and res.record["interrupted_by"] == "SIGINT"
    record = check_consistent(tmp_path / "o", "interrupted")
    assert record["simulated_s"] == 0.5  # the samples were complete; the exports were cut short
    assert {"codes.npz", "samples.csv", "traces.png"} <= set(record["skipped_outputs"])
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # handlers restored


# ---------------------------------------------------------------------------------------------- real processes
def _wait_for_streaming(folder: Path, p, timeout=60.0):
    """Until the run's samples.h5 is being streamed (its temporary file exists), i.e. mid-run."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout:
        if folder.is_dir() and any(n.startswith(".samples.h5.") for n in os.listdir(folder)):
            return
        assert p.poll() is None, p.communicate()
        time.sleep(0.01)
    raise AssertionError("the run never started streaming")


@pytest.mark.stability
def test_sigint_and_sigterm_mid_run_keep_a_consistent_record(tmp_path):
    rounds = 20 if STRESS else 4
    scene = _scene_file(tmp_path, 36000.0, "sig")
    rng = np.random.default_rng(12)
    results = []
    for i in range(rounds):
        sig = (signal.SIGINT, signal.SIGTERM)[i % 2]
        out = tmp_path / f"o{i}"
        p = _bench("run", scene, "--out", out, "--quiet", "--csv")
        _wait_for_streaming(out, p)
        time.sleep(float(rng.uniform(0.0, 0.8)))
        p.send_signal(sig)
        _, err = p.communicate(timeout=120)
        assert p.returncode == 128 + sig, err
        assert "Traceback" not in err
        record = check_consistent(out, "interrupted")
        assert record["interrupted_by"] == signal.Signals(sig).name
        assert 0 < record["simulated_s"] < 36000
        results.append(record["simulated_s"])
    print(f"{rounds} interrupted runs, simulated_s at the stop: {sorted(results)}")


@pytest.mark.stability
def test_a_run_started_with_sigint_ignored_ignores_it_and_still_stops_on_sigterm(tmp_path):
    """A command started in the background of a script inherits SIGINT ignored: the run must not turn that SIGINT
    into a stop (nor swallow the SIGTERM after it): it goes on, and the SIGTERM stops it (exit 143)."""
    scene = _scene_file(tmp_path, 36000.0, "ign")
    out = tmp_path / "o"
    p = _bench("run", scene, "--out", out, "--quiet", preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN))
    _wait_for_streaming(out, p)
    p.send_signal(signal.SIGINT)
    time.sleep(1.0)
    assert p.poll() is None  # still running
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 143 and "Traceback" not in err, err
    assert check_consistent(out, "interrupted")["interrupted_by"] == "SIGTERM"


@pytest.mark.stability
def test_two_concurrent_runs_into_one_folder_never_mix(tmp_path):
    rounds = 10 if STRESS else 2
    scene = _scene_file(tmp_path, 20.0, "conc")
    refusals = {"locked": 0, "not empty": 0}
    for i in range(rounds):
        out = tmp_path / f"o{i}"
        a = _bench("run", scene, "--out", out, "--quiet", "--seed", "1")
        b = _bench("run", scene, "--out", out, "--quiet", "--seed", "2")
        (_, ea), (_, eb) = a.communicate(timeout=300), b.communicate(timeout=300)
        codes = sorted([a.returncode, b.returncode])
        assert codes == [0, 2], (ea, eb)
        loser = ea if a.returncode else eb
        assert ("is writing into this folder" in loser or "not empty" in loser) and "Traceback" not in loser
        refusals["locked" if "is writing into this folder" in loser else "not empty"] += 1
        assert len(loser.strip().splitlines()) == 1
        record = check_consistent(out, "ok")
        winner_seed = 1 if a.returncode == 0 else 2
        assert record["scene"]["seed"] == winner_seed and store.read_attrs(out / "samples.h5")["seed"] == winner_seed
    print(f"{rounds} concurrent pairs: one ran, the other was refused ({refusals})")


def test_a_folder_the_command_made_and_left_empty_is_removed_at_close_and_no_other(tmp_path):
    """A refused or failed command leaves no folder behind: the folder it made and left holding nothing but its
    lock is removed at close (lock and all); a folder that existed before keeps its lock, and a folder holding
    anything else stays."""
    from bench.reporting.outdir import LOCK_NAME, OutFolder

    OutFolder.open(tmp_path / "made" / "deep").close()
    assert not (tmp_path / "made").exists()  # both made by the command (test_outfolder_made.py: the rest of it)
    (tmp_path / "mine").mkdir()
    OutFolder.open(tmp_path / "mine").close()
    assert [p.name for p in (tmp_path / "mine").iterdir()] == [LOCK_NAME]
    with OutFolder.open(tmp_path / "written") as folder:
        folder.write_text("report.md", "# r\n")
    assert sorted(p.name for p in (tmp_path / "written").iterdir()) == [LOCK_NAME, "report.md"]

"""A disk that fills while `run` streams samples.h5: the run ends there, and every sample taken before it is kept —
in a fresh samples.h5 in the out folder, else in the system's temporary folder (named in the error), else the error
says they are lost; never a broken file, a bare HDF5 message or a traceback."""

import errno
import json
import os
import subprocess
import sys
import tempfile
import textwrap

import h5py
import numpy as np
import pytest

from bench.reporting import session, store
from bench.reporting.session import run_to_folder
from bench.running.runner import run_scene
from bench.scenes.scene import parse_scene_text

REST = """
[scene]
name = "rest-full-disk"
duration_s = {duration}
seed = 11
"""


def _scene(duration=6.0):
    return parse_scene_text(REST.format(duration=duration), "rest-full-disk.toml")


def _disk_fills_at_write(monkeypatch, n: int) -> None:
    """The ``n``-th write into an HDF5 dataset (counting from 1) fails as a full disk does; the others succeed."""
    original = h5py.Dataset.__setitem__
    calls = [0]

    def write(self, key, value):
        calls[0] += 1
        if calls[0] == n:
            raise OSError(errno.ENOSPC, "Can't synchronously write data (file write failed: errno = 28, ...)")
        return original(self, key, value)

    monkeypatch.setattr(h5py.Dataset, "__setitem__", write)


def _small_chunks(monkeypatch) -> None:
    """Chunks of 256 samples, flushed every 1024 buffered: a 6 s scene writes many times, as an hour-long one does."""
    monkeypatch.setattr(store, "H5_CHUNK", 256)
    monkeypatch.setattr(store, "FLUSH_SAMPLES", 1024)


def _expected_before(scene, until_s: float) -> dict:
    """The same scene run in memory: each channel's samples taken before ``until_s`` (the run is deterministic)."""
    rec = run_scene(scene, progress=False, keep_samples=True)
    return {n: (r.times[r.times < until_s], r.codes[r.times < until_s], r.status[r.times < until_s])
            for n, r in rec.channels.items()}


def _assert_holds(path, expected) -> None:
    with h5py.File(path, "r") as f:
        assert sorted(f) == sorted(expected)
        for name, (t, code, status) in expected.items():
            assert np.array_equal(f[name]["t"][:], t), name
            assert np.array_equal(f[name]["code"][:], code), name
            assert np.array_equal(f[name]["status"][:], status), name


@pytest.mark.unit
@pytest.mark.parametrize("nth_write", [8, 40])  # the 8th: a channel's instants written, its codes not
def test_a_disk_full_mid_stream_keeps_every_sample_taken_before_it(tmp_path, monkeypatch, nth_write):
    """Prediction (from the run's determinism): samples.h5 holds, bit for bit, each channel's samples taken before
    the instant the run stopped — those already written and those still buffered — and nothing after; its status
    and the record say failed, naming the disk's error in a few words and the seconds kept."""
    _small_chunks(monkeypatch)
    scene = _scene()
    _disk_fills_at_write(monkeypatch, nth_write)
    res = run_to_folder(scene, tmp_path / "o", plots=False, progress=False, chunk_s=0.5)
    stopped = res.record["simulated_s"]
    assert res.exit_code == 1 and res.record["status"] == "failed"
    assert 0 < stopped < scene.duration_s
    error = res.record["error"]
    assert error.startswith(f"writing samples.h5 at {stopped:.3f} s: No space left on device; samples.h5 holds "
                            f"the {stopped:.3f} s recorded before it"), error
    assert "errno = 28" not in error  # HDF5's own text (buffer addresses, times) is not repeated
    assert "samples.h5" in res.record["outputs"] and "codes.npz" in res.record["outputs"]
    monkeypatch.undo()
    _assert_holds(tmp_path / "o" / "samples.h5", _expected_before(scene, stopped))
    with h5py.File(tmp_path / "o" / "samples.h5") as f:
        assert f.attrs["status"] == "failed" and f.attrs["simulated_s"] == stopped
    assert not [p for p in (tmp_path / "o").iterdir() if p.name.endswith(".part")]


@pytest.mark.unit
def test_no_room_left_in_the_out_folder_saves_the_samples_in_the_temporary_folder(tmp_path, monkeypatch):
    """The broken file's space is not enough for the fresh one: the samples go to the system's temporary folder,
    with the umask's mode, and the error names the file; the out folder holds no samples.h5 and no temporary file."""
    _small_chunks(monkeypatch)
    scene = _scene()
    out, tmp = tmp_path / "o", tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    _disk_fills_at_write(monkeypatch, 40)
    written = session.write_recording

    def no_room_in_out(path, rec, compression="gzip"):
        if path.parent == out:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return written(path, rec, compression)

    monkeypatch.setattr(session, "write_recording", no_room_in_out)
    res = run_to_folder(scene, out, plots=False, progress=False, chunk_s=0.5)
    stopped = res.record["simulated_s"]
    saved = list(tmp.glob("biotac-samples-*.h5"))
    assert len(saved) == 1
    assert (f"the {stopped:.3f} s recorded before it were saved as {saved[0]} (no room for them in {out})"
            in res.record["error"]), res.record["error"]
    assert sorted(p.name for p in out.iterdir()) == [".biotac-bench.lock", "record.json", "report.md"]
    assert oct(saved[0].stat().st_mode & 0o777) == oct(0o666 & ~_umask())
    monkeypatch.undo()
    _assert_holds(saved[0], _expected_before(scene, stopped))


def _umask() -> int:
    m = os.umask(0o022)
    os.umask(m)
    return m


@pytest.mark.unit
def test_a_file_size_limit_mid_stream_is_one_line_and_a_complete_record(tmp_path):
    """The kernel refuses the write (RLIMIT_FSIZE, as a quota or a full disk would): exit 1, one error line with the
    system's words, no traceback, no temporary file left, and a record that says what was lost and why.  Under a
    limit every file obeys, the samples cannot be kept anywhere: the error says so rather than pretending."""
    scene = tmp_path / "rest120.toml"
    scene.write_text(REST.format(duration=120.0))
    out = tmp_path / "o"
    script = textwrap.dedent(f"""
        import resource, signal, sys
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, 200_000))
        from bench.cli.main import main
        sys.exit(main(["run", {str(scene)!r}, "--out", {str(out)!r}, "--quiet", "--no-plots"]))
    """)
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300,
                       env={**os.environ, "TMPDIR": str(tmp_path)})
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr and "errno =" not in r.stderr, r.stderr
    errors = [line for line in r.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "writing samples.h5 at " in errors[0] and "File too large" in errors[0], r.stderr
    record = json.loads((out / "record.json").read_text())
    assert record["status"] == "failed" and 0 < record["simulated_s"] < 120
    assert "could not be kept (File too large): they are lost" in record["error"]
    assert sorted(p.name for p in out.iterdir()) == [".biotac-bench.lock", "record.json", "report.md"]
    assert not list(tmp_path.glob("biotac-samples-*"))  # the temporary folder's attempt left nothing either


@pytest.mark.unit
def test_a_run_simulated_to_its_end_whose_export_fails_says_so(tmp_path, monkeypatch, capsys):
    """An output that cannot be written after the whole scene was simulated is not "the run stopped at": the line
    says the run failed after all of it was simulated, and names the file."""
    from bench.cli.main import main
    from bench.reporting import exports

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(exports, "export_npz", full)
    assert main(["run", "rest", "--out", str(tmp_path / "o"), "--quiet", "--no-plots"]) == 1
    err = capsys.readouterr().err
    assert "error: the run failed after all 10 s were simulated: writing codes.npz: OSError: [Errno 28] No space " \
           "left on device" in err, err


@pytest.mark.unit
def test_a_disk_full_as_samples_h5_is_created_leaves_no_temporary_file(tmp_path, monkeypatch):
    """The disk is full already when samples.h5 is created (its temporary file made, HDF5's header not written):
    the error reaches the caller, naming the disk's error, and the out folder keeps no half-written temporary
    file: the folder it made, left holding nothing but its lock, is removed."""
    from bench.reporting.outdir import OutFolder

    def full(path, *args, **kwargs):
        path.write_bytes(b"\x89HDF\r\n\x1a\n half a header")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(session, "SampleStore", full)
    out = tmp_path / "o"
    with pytest.raises(OSError, match="No space left on device"):
        run_to_folder(_scene(0.5), out, plots=False, progress=False)
    assert not out.exists()  # no temporary file, and the folder it made, left holding only its lock, is removed
    OutFolder.open(out).close()  # not locked any more


@pytest.mark.unit
def test_the_broken_samples_file_is_deleted_before_the_samples_are_written_again(tmp_path, monkeypatch):
    """On a full disk the broken file's space is what the fresh samples.h5 needs (session: "delete the broken file
    (which frees its space) and write those samples into a fresh one"): when the fresh file is written, the broken
    one is gone from the out folder."""
    _small_chunks(monkeypatch)
    out = tmp_path / "o"
    _disk_fills_at_write(monkeypatch, 40)
    written = session.write_recording
    beside = []

    def note_what_is_beside(path, rec, compression="gzip"):
        beside.append(sorted(p.name for p in out.iterdir() if p.name.startswith(".samples.h5.") and p != path))
        return written(path, rec, compression)

    monkeypatch.setattr(session, "write_recording", note_what_is_beside)
    res = run_to_folder(_scene(), out, plots=False, progress=False, chunk_s=0.5)
    assert res.record["status"] == "failed" and "samples.h5 holds" in res.record["error"], res.record["error"]
    assert beside == [[]]


@pytest.mark.unit
@pytest.mark.parametrize("run_error", [None, "NumericalError: NaN at the ADC"])
def test_a_disk_full_when_samples_h5_is_closed_keeps_every_sample(tmp_path, monkeypatch, run_error):
    """HDF5 writes its cached metadata only when the file is flushed and closed, so a disk that fills after the last
    sample was taken fails there (seen on a 200 kB tmpfs: "Slist already enabled?"); every sample of the run is
    still kept, read back before the broken file is closed — they were deleted with it, and the record named HDF5's
    words only — and a failure of the run itself stays in the error beside it."""
    scene = _scene()
    if run_error:
        ran = session.run_scene

        def failing(*a, **kw):
            rec = ran(*a, **kw)
            rec.status, rec.error = "failed", run_error
            return rec

        monkeypatch.setattr(session, "run_scene", failing)
    flush, calls = h5py.File.flush, []

    def full_once(self):
        calls.append(self.filename)
        if len(calls) == 1:
            raise OSError(errno.ENOSPC, "Can't write data (file write failed: errno = 28, ...)")
        return flush(self)

    monkeypatch.setattr(h5py.File, "flush", full_once)
    out = tmp_path / "o"
    res = run_to_folder(scene, out, plots=False, progress=False, chunk_s=0.5)
    monkeypatch.undo()
    assert res.exit_code == 1 and res.record["status"] == "failed" and res.record["simulated_s"] == scene.duration_s
    assert res.record["error"] == ((f"{run_error}; " if run_error else "") + "writing samples.h5 at 6.000 s: No space "
                                   "left on device; samples.h5 holds the 6.000 s recorded before it"), res.record["error"]
    assert "samples.h5" in res.record["outputs"]
    _assert_holds(out / "samples.h5", _expected_before(scene, scene.duration_s))


@pytest.mark.unit
@pytest.mark.parametrize("error, reason", [
    (OSError(errno.ENOSPC, "Can't write"), "No space left on device"),
    (OSError("Unable to flush file (file write failed: time = Tue Nov 24 09:48:53 2026\n, filename = 'x.h5', "
             "file descriptor = 7, errno = 28, error message = 'No space left on device', buf = 0x5581, "
             "total write size = 4096)"), "No space left on device"),
    (RuntimeError("Slist already enabled? (slist already enabled?)\nsecond line"),
     "Slist already enabled? (slist already enabled?)"),
    (RuntimeError(), "RuntimeError"),  # an empty message: the reason still marks the failure
])
def test_os_reason_is_the_systems_words_for_hdf5s_errno_else_the_first_line(error, reason):
    """HDF5's errors reach Python without an errno, their text spanning lines of buffer addresses and times: the
    reason is the system's text for the errno the message names, else the message's first line."""
    assert store.os_reason(error) == reason


@pytest.mark.unit
def test_samples_saved_elsewhere_are_named_when_record_json_cannot_be_written(tmp_path, monkeypatch, capsys):
    """Seen on a 200 kB tmpfs: samples.h5 did not fit (saved in the system's temporary folder), then record.json did
    not fit either; its one error line must name where the samples went — it said only that record.json was
    missing, and the only file naming them was report.md."""
    from bench import atomic
    from bench.cli.main import main

    out, tmp = tmp_path / "o", tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    flush, written, commit = h5py.File.flush, session.write_recording, atomic.commit

    def full_once(self, calls=[]):
        calls.append(1)
        if len(calls) == 1:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return flush(self)

    def no_room_in_out(path, rec, compression="gzip"):
        if path.parent == out:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return written(path, rec, compression)

    def no_room_for_the_record(tmp_file, final):
        if final.name == "record.json":
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return commit(tmp_file, final)

    monkeypatch.setattr(h5py.File, "flush", full_once)
    monkeypatch.setattr(session, "write_recording", no_room_in_out)
    monkeypatch.setattr(atomic, "commit", no_room_for_the_record)
    assert main(["run", "rest", "--out", str(out), "--quiet", "--no-plots"]) == 1
    err = capsys.readouterr().err
    (saved,) = tmp.glob("biotac-samples-*.h5")
    lines = [line for line in err.splitlines() if line.startswith("error:")]
    assert len(lines) == 1 and f"{out}/record.json could not be written" in lines[0], err
    assert f"the 10.000 s recorded before it were saved as {saved}" in lines[0], err


@pytest.mark.unit
def test_a_samples_file_that_fails_to_close_is_never_taken_for_a_written_one(tmp_path, monkeypatch):
    """HDF5 may report the full disk only as the file closes: the run must not call such a samples.h5 written (it
    would be listed in the record, broken or missing), but keep its samples as for any failed write or say they are
    lost."""
    scene = _scene()
    close = h5py.File.close

    def full_at_close(self):
        streamed = bool(self) and self.filename.endswith(".part")  # the stream's file, not a fresh one
        close(self)
        if streamed and not getattr(full_at_close, "done", False):
            full_at_close.done = True
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(h5py.File, "close", full_at_close)
    res = run_to_folder(scene, tmp_path / "o", plots=False, progress=False, chunk_s=0.5)
    monkeypatch.undo()
    assert res.record["status"] == "failed" and res.record["error"].startswith(
        "writing samples.h5 at 6.000 s: No space left on device; "), res.record["error"]
    assert "samples.h5" not in res.record["outputs"] or "samples.h5 holds the 6.000 s" in res.record["error"]

"""Fixes from a fresh user's review: one signal during ``run`` stops only the simulation (exports and plots are
still written), only a signal while the outputs are written stops them."""

import json
import os
import signal
import time

import numpy as np
import pytest

from bench.reporting import exports
from bench.reporting.session import run_to_folder
from bench.scenes.scene import parse_scene
from bench.tests.test_outputs import _bench, _scene_file, _wait_for_streaming, check_consistent

PLOTS = ("traces.png", "spectrogram.png")


def _check_everything_written_for_the_recorded_part(out, record: dict, duration_s: float) -> None:
    """Exports and plots all written, nothing skipped, and the exports hold the recorded part only."""
    assert 0 < record["simulated_s"] < duration_s
    assert {"samples.h5", "codes.npz", "samples.csv", *PLOTS} <= set(record["outputs"]), record["outputs"]
    assert "skipped_outputs" not in record, record.get("skipped_outputs")
    for name in PLOTS:
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    times = np.loadtxt(out / "samples.csv", delimiter=",", skiprows=1, usecols=0)
    assert times.size == sum(c["samples"] for c in record["channels"].values())
    assert times.max() < record["simulated_s"]
    npz_last = max(float(a[-1]) for k, a in np.load(out / "codes.npz").items() if k.endswith("_t") and a.size)
    assert abs(npz_last - times.max()) < 1e-6  # the CSV rounds the instants


@pytest.mark.stability
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_one_signal_mid_simulation_still_writes_exports_and_plots(tmp_path, sig):
    """As the review's `run midrest.toml --csv` (a 590 s rest scene) with one signal mid-simulation."""
    duration_s = 590.0
    scene = _scene_file(tmp_path, duration_s, "midrest")
    out = tmp_path / "o"
    p = _bench("run", scene, "--out", out, "--quiet", "--csv")
    _wait_for_streaming(out, p)
    time.sleep(0.5)
    p.send_signal(sig)
    _, err = p.communicate(timeout=180)
    assert p.returncode == 128 + sig, err  # README / run --help: 130 for SIGINT, 143 for SIGTERM
    assert "Traceback" not in err and "arrived while the outputs" not in err, err
    record = check_consistent(out, "interrupted")  # codes.npz equals samples.h5, which holds simulated_s exactly
    assert record["interrupted_by"] == sig.name
    _check_everything_written_for_the_recorded_part(out, record, duration_s)


def _signal_at_first_chunk(monkeypatch, sig=signal.SIGINT):
    """The run gets ``sig`` at its first chunk boundary, i.e. mid-simulation (deterministic, in this process)."""
    from bench.reporting import session

    original = session.run_scene

    def run_scene(*args, should_stop, **kw):
        def stop_asked():
            if not sent:
                sent.append(sig)
                os.kill(os.getpid(), sig)
            return should_stop()

        sent = []
        return original(*args, should_stop=stop_asked, **kw)

    monkeypatch.setattr(session, "run_scene", run_scene)


@pytest.mark.unit
def test_one_signal_mid_simulation_in_process_writes_everything(tmp_path, monkeypatch):
    _signal_at_first_chunk(monkeypatch)
    sc = parse_scene({"scene": {"name": "w", "duration_s": 3.0}})
    res = run_to_folder(sc, tmp_path / "o", csv=True, progress=False, chunk_s=0.5)
    assert res.exit_code == 130 and res.record["interrupted_by"] == "SIGINT"
    record = check_consistent(tmp_path / "o", "interrupted")
    _check_everything_written_for_the_recorded_part(tmp_path / "o", record, 3.0)
    assert record["simulated_s"] == 0.5


@pytest.mark.unit
def test_a_second_signal_while_writing_stops_the_exports_and_plots(tmp_path, monkeypatch):
    """SIGINT mid-simulation, then SIGTERM as samples.csv starts: codes.npz (written before) is kept; samples.csv
    and the plots are skipped with the signal that stopped them; the status and exit code are the first signal's."""
    _signal_at_first_chunk(monkeypatch)
    original = exports.export_csv

    def signalled_csv(h5, dest, base, checkpoint):
        os.kill(os.getpid(), signal.SIGTERM)
        original(h5, dest, base, checkpoint)

    monkeypatch.setattr(exports, "export_csv", signalled_csv)
    sc = parse_scene({"scene": {"name": "w", "duration_s": 3.0}})
    res = run_to_folder(sc, tmp_path / "o", csv=True, progress=False, chunk_s=0.5)
    assert res.exit_code == 130 and res.record["interrupted_by"] == "SIGINT"
    record = check_consistent(tmp_path / "o", "interrupted")
    assert "codes.npz" in record["outputs"] and record["simulated_s"] == 0.5
    assert set(record["skipped_outputs"]) == {"samples.csv", *PLOTS}
    for why in record["skipped_outputs"].values():
        assert why == "not written: SIGTERM arrived while the outputs were being written"
    assert json.loads((tmp_path / "o" / "record.json").read_text()) == record
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # handlers restored


# --- record: never a silent overwrite, never a file named like a folder ------------------------------------------
def _record(port, out, *extra):
    from bench.tests.cli_runs import run_cli

    return run_cli("record", port, "--out", out, "--quiet", *extra, timeout=120)


@pytest.mark.unit
@pytest.mark.parametrize("given", ["new/", "existing", "existing/"])
def test_record_refuses_a_folder_as_out_and_writes_nothing(tmp_path, given):
    """`record --out dir/` used to write a FILE named dir; an existing folder or a path ending in / is refused."""
    (tmp_path / "existing").mkdir()
    r = _record("loop://", f"{tmp_path}/{given}")
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert "argument --out" in r.stderr and "is a folder" in r.stderr and "recording.npz" in r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["existing"] and not any((tmp_path / "existing").iterdir())


@pytest.mark.unit
@pytest.mark.parametrize("earlier, csv", [(("rec.npz",), ()), (("rec.npz", "rec.csv"), ()), (("rec.csv",), ()),
                                          (("rec.npz",), ("--csv",))],
                         ids=["npz", "npz and csv", "a csv alone", "npz, asked for csv"])
def test_record_refuses_an_earlier_recording_before_opening_the_port(tmp_path, earlier, csv):
    """Refused before the port is opened (loop:// would otherwise be read), naming the files and --force."""
    for name in earlier:
        (tmp_path / name).write_text("earlier")
    r = _record("loop://", tmp_path / "rec.npz", *csv)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert r.stderr.startswith("error: --out ") and "--force" in r.stderr
    assert all(str(tmp_path / name) in r.stderr for name in earlier)
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == dict.fromkeys(earlier, "earlier")


@pytest.mark.unit
def test_record_refuses_an_out_its_csv_would_overwrite(tmp_path):
    r = _record("loop://", tmp_path / "rec.csv", "--csv", "--force")
    assert r.returncode == 2 and "over it" in r.stderr and str(tmp_path / "rec.npz") in r.stderr, r.stderr
    assert not any(tmp_path.iterdir())


@pytest.mark.firmware
def test_record_force_replaces_the_earlier_recording_and_its_csv_consistently(tmp_path):
    from bench.hosts.bridge import FirmwareBench

    out, csv = tmp_path / "rec.npz", tmp_path / "rec.csv"
    with FirmwareBench(1) as fb:
        first = _record(fb.port, out, "--seconds", "0.3", "--csv")
        assert first.returncode == 0, first.stderr
        assert len(np.load(out)["seq"]) == 30 and csv.read_text().count("\n") == 1 + 30 * 44
        again = _record(fb.port, out, "--seconds", "0.2")
        assert again.returncode == 2 and "--force" in again.stderr, again.stderr
        assert len(np.load(out)["seq"]) == 30 and csv.exists()  # untouched
        forced = _record(fb.port, out, "--seconds", "0.2", "--force")
        assert forced.returncode == 0, forced.stderr
        assert len(np.load(out)["seq"]) == 20 and not csv.exists()  # the earlier CSV would not match: removed
        with_csv = _record(fb.port, out, "--seconds", "0.1", "--force", "--csv")
        assert with_csv.returncode == 0, with_csv.stderr
    assert len(np.load(out)["seq"]) == 10 and csv.read_text().count("\n") == 1 + 10 * 44
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv", "rec.npz"]  # no temporary file left

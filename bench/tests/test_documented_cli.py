"""Documented command-line behaviours that had no test of their own (README audit): ``run --compression``,
``explore``'s fresh default out folder, ``explore`` stopped by Ctrl-C / SIGTERM, ``--scheduler`` on an existing
Dask cluster (and a clear error for an address where none answers), and ``rtl lint`` / ``rtl vectors --waves``."""

import json
import os
import signal
import socket
import subprocess
import time
from pathlib import Path

import pytest

from bench.cli import main as cli
from bench.experiments import experiment as E
from bench.paths import FIXTURES, REPO
from bench.tests import test_sweep_review as sweep_review
from bench.tests.cli_runs import CLI
from bench.tests.test_sweep_review import TINY

unit = pytest.mark.unit
no_cluster = sweep_review.no_cluster  # the fixture: explore's trials in this process, no LocalCluster
QUICK = FIXTURES / "experiments" / "quick.toml"

# --- run --compression ------------------------------------------------------------------------------------------

SHORT_SCENE = '[scene]\nname = "short"\nduration_s = 0.2\n[host]\nsequence = ["PAC", "PDC"]\n'


def _dataset_filters(h5_path: Path) -> dict:
    """{dataset name: (compression, compression_opts, shuffle)} for every dataset in the file."""
    import h5py

    found = {}

    def note(name, obj) -> None:  # returns None: visititems stops at the first other value
        if isinstance(obj, h5py.Dataset):
            found[name] = (obj.compression, obj.compression_opts, obj.shuffle)

    with h5py.File(h5_path, "r") as f:
        f.visititems(note)
    return found


@unit
@pytest.mark.parametrize("flag, filters", [(None, ("gzip", 1, True)),  # the default: gzip level 1 + shuffle
                                           ("gzip", ("gzip", 1, True)),
                                           ("lzf", ("lzf", None, True)),
                                           ("none", (None, None, False))])
def test_run_compression_sets_the_filter_of_every_dataset_in_samples_h5(tmp_path, flag, filters):
    scene = tmp_path / "short.toml"
    scene.write_text(SHORT_SCENE)
    out = tmp_path / "out"
    argv = ["run", str(scene), "--out", str(out), "--quiet", "--no-plots"]
    assert cli.main(argv + ([] if flag is None else ["--compression", flag])) == 0
    found = _dataset_filters(out / "samples.h5")
    assert {n.split("/")[0] for n in found} == {"PAC", "PDC"} and len(found) == 6  # t, code, status per channel
    assert set(found.values()) == {filters}, found


@unit
def test_run_refuses_an_unknown_compression_in_one_line_before_running(tmp_path, capsys):
    scene = tmp_path / "short.toml"
    scene.write_text(SHORT_SCENE)
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as stop:
        cli.main(["run", str(scene), "--out", str(out), "--quiet", "--compression", "zstd"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert "--compression" in err and '"zstd"' in err and "gzip" in err and "Traceback" not in err, err
    assert not out.exists()  # refused before anything ran


# --- explore: a fresh out/explore/<name>[-n] without --out -------------------------------------------------------


@unit
def test_explore_without_out_writes_a_fresh_folder_each_time_and_keeps_the_cache(tmp_path, monkeypatch, no_cluster,
                                                                                 capsys):
    """README: "without --out each run gets a fresh … out/explore/<name>[-n]" (relative to the working folder), and
    the stage cache is kept, so the second run slides nothing."""
    monkeypatch.chdir(tmp_path)
    argv = ["explore", str(QUICK), "--cache", str(tmp_path / "cache"), "--quiet"]
    assert cli.main(argv) == 0
    first = tmp_path / "out" / "explore" / "quick"
    assert (first / "report.md").exists() and (first / "summary.json").exists()
    before = {p.name: p.read_bytes() for p in first.iterdir()}
    capsys.readouterr()
    monkeypatch.setattr(E, "sweep", lambda *a, **k: pytest.fail("a cached stage ran trials again"))
    assert cli.main(argv) == 0
    second = tmp_path / "out" / "explore" / "quick-2"
    assert f"wrote {Path('out', 'explore', 'quick-2')}/" in capsys.readouterr().out
    assert (second / "accuracy.csv").read_bytes() == before["accuracy.csv"]  # the same results, from the cache
    assert {p.name: p.read_bytes() for p in first.iterdir()} == before  # the first run's folder untouched
    assert sorted(p.name for p in (tmp_path / "out" / "explore").iterdir()) == ["quick", "quick-2"]


# --- explore stopped by a signal ---------------------------------------------------------------------------------


def _explore_then_signal(tmp_path, send) -> tuple[subprocess.Popen, str, list, Path, float]:
    """``explore quick.toml`` on a one-worker LocalCluster in its own process group; once its pilot trials run,
    ``send(proc)``.  Returns the process (ended), its stderr, its child processes at the signal, its out folder and
    the seconds from the signal to its end."""
    import psutil

    out, err_path = tmp_path / "res", tmp_path / "stderr.txt"
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    with open(err_path, "w") as err:
        proc = subprocess.Popen([*CLI, "explore", str(QUICK), "--workers", "1", "--quiet", "--out", str(out),
                                 "--cache", str(tmp_path / "cache")], cwd=tmp_path, env=env,
                                stdout=subprocess.DEVNULL, stderr=err, start_new_session=True)
    try:
        deadline = time.monotonic() + 90
        while "pilot:" not in err_path.read_text() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)  # "pilot: N trials" is said once the cluster is up, as the trials are sent
        assert proc.poll() is None and "pilot:" in err_path.read_text(), err_path.read_text()
        time.sleep(1.5)  # the worker is running pilot trials
        children = psutil.Process(proc.pid).children(recursive=True)
        assert children, "no worker process"
        send(proc)
        t0 = time.monotonic()
        proc.wait(timeout=60)
        took = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    return proc, err_path.read_text(), children, out, took


@unit
@pytest.mark.parametrize("signum, status, said, whom", [
    (signal.SIGINT, 130, "interrupted", "group"),  # a terminal's Ctrl-C reaches the whole process group
    (signal.SIGTERM, 143, "terminated", "main"),  # `timeout` signals the main process only
])
def test_explore_stopped_by_a_signal_ends_with_one_line_and_its_exit_status(tmp_path, signum, status, said, whom):
    import psutil

    def send(proc):
        (os.killpg if whom == "group" else os.kill)(proc.pid, signum)

    proc, stderr, children, out, took = _explore_then_signal(tmp_path, send)
    assert proc.returncode == status, stderr
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr, stderr
    assert stderr.strip().splitlines()[-1] == said and stderr.count(said) == 1, stderr
    assert not out.exists()  # nothing written, nothing half-written: the folder it made is gone
    assert took < 15, f"the exit took {took:.1f} s"
    assert not psutil.wait_procs(children, timeout=10)[1]  # the worker is gone too


# --- --scheduler: an existing cluster by address -----------------------------------------------------------------


@pytest.fixture
def tcp_cluster():
    """A one-worker Dask cluster in this process, listening on tcp:// as `dask scheduler` does."""
    from distributed import LocalCluster

    # no dashboard, and the scheduler's HTTP server on any free port (8787 may be taken: distributed would warn)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp", host="127.0.0.1",
                      dashboard_address=None, scheduler_kwargs={"dashboard_address": ":0"}) as cluster:
        yield cluster


def _tasks_run_by(cluster) -> int:
    """How many tasks the cluster's workers have run."""
    return sum(worker.state.executed_count for worker in cluster.workers.values())


@unit
def test_texture_sweep_runs_its_trials_on_the_scheduler_given(tmp_path, tcp_cluster, capsys):
    address = tcp_cluster.scheduler_address
    assert address.startswith("tcp://") and _tasks_run_by(tcp_cluster) == 0
    out = tmp_path / "sweep"
    assert cli.main(["texture-sweep", "--textures", "902", "--movements", "7,14", "--trials", "1", "--quiet",
                     "--scheduler", address, "--out", str(out)]) == 0
    assert _tasks_run_by(tcp_cluster) > 0  # the trials ran there, not on a LocalCluster of its own
    assert f"on scheduler {address}" in capsys.readouterr().err
    record = json.loads((out / "trials.json").read_text())
    assert record["workers"] == f"scheduler {address}" and len(record["rows"]) == 2


@unit
def test_explore_runs_its_trials_on_the_scheduler_given(tmp_path, tcp_cluster, capsys):
    experiment = tmp_path / "tiny.toml"
    experiment.write_text(TINY.format(max_moves=10))
    address = tcp_cluster.scheduler_address
    out = tmp_path / "res"
    assert cli.main(["explore", str(experiment), "--quiet", "--scheduler", address, "--out", str(out),
                     "--cache", str(tmp_path / "cache")]) == 0
    assert _tasks_run_by(tcp_cluster) > 0
    assert f"== baseline: scheduler {address}" in capsys.readouterr().err
    assert (out / "report.md").exists()


def _closed_port() -> int:
    """A local TCP port that nothing listens on (just freed)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@unit
@pytest.mark.parametrize("command", [["texture-sweep", "--textures", "902", "--movements", "7", "--trials", "1"],
                                     ["explore", str(QUICK), "--no-cache"]])
def test_a_scheduler_address_where_none_answers_is_a_one_line_error_within_seconds(tmp_path, command, capsys):
    address = f"tcp://127.0.0.1:{_closed_port()}"
    t0 = time.monotonic()
    status = cli.main([*command, "--quiet", "--scheduler", address, "--out", str(tmp_path / "o")])
    took = time.monotonic() - t0
    err = capsys.readouterr().err
    assert status == 2, err
    errors = [line for line in err.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and errors[0] == err.strip().splitlines()[-1], err
    assert errors[0].startswith(f"error: no Dask scheduler answers at {address}") and "Traceback" not in err, err
    assert took < 20, f"the error took {took:.1f} s"
    assert not (tmp_path / "o").exists()  # nothing written: the folder it made is gone


# --- rtl lint, rtl vectors --waves -------------------------------------------------------------------------------


@pytest.mark.rtl
def test_rtl_lint_passes_the_shipped_rtl_and_fails_on_a_warning(tmp_path, monkeypatch, capsys):
    """`rtl lint` is verilator --lint-only -Wall: exit 0 on the shipped RTL; a width truncation added to it is
    printed and fails the command."""
    from emulator.rtl import build

    assert cli.main(["rtl", "lint"]) == 0, capsys.readouterr()
    capsys.readouterr()
    source = build.SOURCES[0].read_text()
    end = source.rindex("endmodule")
    edited = tmp_path / build.SOURCES[0].name
    edited.write_text(source[:end] + "    wire [1:0] lint_probe = 4'd5;\n" + source[end:])
    monkeypatch.setattr(build, "SOURCES", [edited, *build.SOURCES[1:]])
    assert cli.main(["rtl", "lint"]) != 0
    said = capsys.readouterr().out
    assert "lint_probe" in said and "%Warning-WIDTH" in said, said


@pytest.mark.rtl
def test_rtl_vectors_with_waves_replays_the_file_and_writes_a_waveform(capsys):
    """Builds into out/rtl_build_waves/ on first use (about 40 s), reused afterwards."""
    started_ns = time.time_ns()
    assert cli.main(["rtl", "vectors", str(FIXTURES / "spi_vectors" / "properties.json"), "--waves"]) == 0
    said, err = capsys.readouterr()
    assert "properties.json: 88 transfers, 0 differ from the reference" in said, said
    (line,) = [x for x in said.splitlines() if x.startswith("waveforms: ")]
    files = [Path(p) for p in line.removeprefix("waveforms: ").split(", ")]
    assert files and all(p.parent == REPO / "out" / "rtl_build_waves" for p in files), files
    # without the lz4 headers the waves are VCD, and the command says why (README)
    assert ("writing VCD instead" in err) == any(p.suffix == ".vcd" for p in files), err
    for wave in files:
        assert wave.suffix in (".fst", ".vcd") and wave.stat().st_size > 1000
        assert wave.stat().st_mtime_ns >= started_ns - 2_000_000_000  # written by this run, not left from before


@pytest.mark.rtl
def test_rtl_vectors_fails_on_a_word_or_an_unrequested_conversion_and_reads_words_as_numbers(tmp_path, capsys):
    """`rtl vectors` compares every MISO word and ADC request with the file and exits 1 if any differ: a word
    changed, or a recorded conversion the RTL never asks for (it was not counted: exit 0); a word merely spelled
    upper-case or zero-padded is the same word (it was compared as text: exit 1)."""
    import json

    vec = json.loads((FIXTURES / "spi_vectors" / "fault_truncated_word.json").read_text())
    spelled = json.loads(json.dumps(vec))
    spelled["transfers"][-1]["miso"] = "0x" + vec["transfers"][-1]["miso"].upper().zfill(4)
    changed = json.loads(json.dumps(vec))
    changed["transfers"][-1]["miso"] = f"{int(vec['transfers'][-1]['miso'], 16) ^ 0x0100:x}"
    extra = json.loads(json.dumps(vec))
    extra["conversions"].append({**vec["conversions"][-1], "t_ps": vec["conversions"][-1]["t_ps"] + 500_000_000})
    files = {}
    for name, v in (("spelled", spelled), ("changed", changed), ("extra", extra)):
        files[name] = tmp_path / f"{name}.json"
        files[name].write_text(json.dumps(v))
    assert cli.main(["rtl", "vectors", str(files["spelled"])]) == 0, capsys.readouterr()
    assert "spelled.json: 3 transfers, 0 differ from the reference" in capsys.readouterr().out
    assert cli.main(["rtl", "vectors", str(files["changed"]), str(files["extra"])]) == 1
    said = capsys.readouterr().out
    assert "changed.json: 3 transfers, 1 differ from the reference" in said, said
    # which transfer, the word expected and the word the RTL gave: a failed CI log says where to look
    last = vec["transfers"][-1]
    width = (last["nbits"] + 3) // 4
    assert (f"  transfer 2 at {last['t_ps'] / 1e6:g} µs (select {last['cs']}, {last['nbits']} bits, MOSI "
            f"{last['mosi']}): MISO {int(changed['transfers'][-1]['miso'], 16):0{width}x} expected, the RTL gave "
            f"{int(last['miso'], 16):0{width}x}") in said, said
    assert said.count("  transfer ") == 1, said
    assert "extra.json: 3 transfers, 0 differ from the reference, 1 recorded conversions never requested" in said


@pytest.mark.rtl
def test_rtl_vectors_runs_a_file_with_a_biotac_sp_on_an_rtl_built_for_it(capsys):
    """Files for different mixes of variants in one command: each runs on an RTL built for its SP mask (the
    BioTac-only file on the default build, the SP beside a partial BioTac on out/rtl_build_sp1/), and each is
    reported; exit 0 as both match."""
    sp_file, plain = (FIXTURES / "spi_vectors" / f"{n}.json" for n in ("variants_and_provided", "properties"))
    assert cli.main(["rtl", "vectors", str(sp_file), str(plain)]) == 0
    said = capsys.readouterr().out
    n_sp = len(json.loads(sp_file.read_text())["transfers"])
    assert f"variants_and_provided.json: {n_sp} transfers, 0 differ from the reference" in said, said
    assert "properties.json: 88 transfers, 0 differ from the reference" in said, said
    assert (REPO / "out" / "rtl_build_sp1" / "sp_mask.txt").read_text() == "1"

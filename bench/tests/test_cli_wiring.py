"""Flags the README documents reach what they drive (a README audit broke each and no test noticed): the command
line runs in process with the heavy step replaced by a recorder that stops the command there, so each test checks
what the flag handed on, in well under a second."""

import os

import pytest

from bench.cli.main import main

pytestmark = pytest.mark.unit


class Handed(Exception):
    """Raised by a recorder: the command got as far as the heavy step, with these keywords."""

    def __init__(self, kw):
        super().__init__("recorded")
        self.kw = kw


def recorder(*args, **kw):
    raise Handed({"args": args, **kw})


def handed(argv) -> dict:
    with pytest.raises(Handed) as caught:
        main([str(a) for a in argv])
    return caught.value.kw


@pytest.mark.parametrize("flag,npz", [([], None), (["--npz"], True)])
def test_run_npz_forces_the_exports(monkeypatch, tmp_path, flag, npz):
    """README: `--npz` forces codes.npz and the CSV exports (past the 600 s a run writes them by default)."""
    import bench.reporting.session as session

    monkeypatch.setattr(session, "run_to_folder", recorder)
    assert handed(["run", "rest", "--out", tmp_path / "run", "--quiet", *flag])["npz"] is npz


@pytest.mark.parametrize("flags,realtime,rx_buffer", [([], True, 4096), (["--fast", "--rx-buffer", "8192"], False, 8192)])
def test_bridge_fast_and_rx_buffer_reach_the_bench(monkeypatch, flags, realtime, rx_buffer):
    """README: paced to the wall clock unless `--fast` (unpaced: the firmware waits for a reading host); the host's
    receive buffer is `--rx-buffer` bytes (4096 by default), as the start-up line says."""
    import bench.hosts.bridge as bridge

    monkeypatch.setattr(bridge, "FirmwareBench", recorder)
    kw = handed(["bridge", "--seconds", "1", *flags])
    assert (kw["realtime"], kw["rx_buffer"]) == (realtime, rx_buffer)


def test_explore_ablation_all_runs_every_ablation(monkeypatch, tmp_path):
    """README: `--ablation all` runs each variant beside the baseline (and, with `--no-cache`, caches nothing)."""
    import bench.experiments.experiment as E

    made = []
    original = E.ablated
    monkeypatch.setattr(E, "ablated", lambda spec, name: made.append(name) or original(spec, name))
    monkeypatch.setattr(E, "run_experiment", recorder)
    kw = handed(["explore", "fixtures/experiments/quick.toml", "--ablation", "all", "--no-cache",
                 "--out", tmp_path / "x", "--quiet"])
    assert made == list(E.ABLATIONS) and len(made) > 1
    assert kw["cache_dir"] is None
    kw = handed(["explore", "fixtures/experiments/quick.toml", "--cache", tmp_path / "cache",
                 "--out", tmp_path / "y", "--quiet"])
    assert os.path.samefile(kw["cache_dir"], tmp_path / "cache")


def test_a_local_cluster_has_one_worker_per_core_by_default(monkeypatch):
    """README: campaigns run on a LocalCluster of one worker process per core unless `--workers` says otherwise."""
    from bench.campaigns import engine

    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    monkeypatch.setattr(engine.os, "cpu_count", lambda: 3)
    assert engine.ClusterSpec.from_env().n_workers == 3
    assert engine.ClusterSpec.from_env(workers=1).n_workers == 1
    assert engine.ClusterSpec.from_env().describe() == "LocalCluster, 3 worker(s)"

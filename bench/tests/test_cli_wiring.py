"""Flags the README documents reach what they drive (a README audit broke each and no test noticed): the command
line runs in process with the heavy step replaced by a recorder that stops the command there, so each test checks
what the flag handed on, in well under a second."""

import os
import re

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


@pytest.mark.parametrize("flags,baud", [([], 3_000_000), (["--baud", "57600"], 57600)])
def test_bridge_and_record_baud_reaches_the_line(monkeypatch, tmp_path, flags, baud):
    """README: the bridge's UART runs at `--baud`, 3 Mbaud by default (so a 14.3 kB/s stream never fills the line);
    `record` opens its port at the same rate unless told otherwise."""
    import bench.hosts.bridge as bridge
    import bench.hosts.driver as driver

    monkeypatch.setattr(bridge, "FirmwareBench", recorder)
    assert handed(["bridge", "--seconds", "1", *flags])["baudrate"] == baud
    monkeypatch.setattr(driver, "BridgeDriver", recorder)
    assert handed(["record", "loop://", "--seconds", "1", "--out", tmp_path / "r.npz", *flags])["baudrate"] == baud


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
    # (the stand-in run stops the command, which then removes the empty cache folder it made: compare paths)
    assert os.path.realpath(kw["cache_dir"]) == os.path.realpath(tmp_path / "cache")


def test_a_local_cluster_has_one_worker_per_core_by_default(monkeypatch):
    """README: campaigns run on a LocalCluster of one worker process per core unless `--workers` says otherwise."""
    from bench.campaigns import engine

    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    monkeypatch.setattr(engine.os, "cpu_count", lambda: 3)
    assert engine.ClusterSpec.from_env().n_workers == 3
    assert engine.ClusterSpec.from_env(workers=1).n_workers == 1
    assert engine.ClusterSpec.from_env().describe() == "LocalCluster, 3 worker(s)"


def test_claims_fidelity_seed_and_quick_reach_the_bench(monkeypatch):
    """README: `claims --fidelity reference --seed 7 --quick --only …` runs the claims on that profile and seed
    (docs/model.md's sliding claims at the reference profile are run this way)."""
    import bench.verification.claims as claims

    monkeypatch.setattr(claims, "Bench", recorder)
    kw = handed(["claims", "--fidelity", "reference", "--seed", "7", "--quick", "--only", "noise"])
    assert (kw["fidelity"], kw["seed"], kw["quick"]) == ("reference", 7, True)
    kw = handed(["claims", "--only", "noise"])
    assert (kw["fidelity"], kw["quick"]) == ("default", False)


def test_noise_budget_json_has_the_documented_fields(capsys):
    """`noise-budget --json`: one object per line of the budget with source, channel, rti_uV, pac_bits and note;
    every channel of the table is there (PAC, PDC, TAC, TDC and the electrodes)."""
    import json

    assert main(["noise-budget", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert rows and all(set(r) >= {"source", "channel", "rti_uV", "pac_bits", "note"} for r in rows)
    channels = {r["channel"] for r in rows}
    assert {"PAC", "PDC", "TAC", "TDC"} <= channels and any(c.startswith("E") for c in channels)


def test_noise_budget_takes_a_unit_and_a_variant(capsys):
    """`noise-budget --unit 17 --variant biotac-sp`: the SP's 24 electrodes (the BioTac's 19 by default), each with
    the reference noise at that unit's own resting code — ppm × the code a noise-free Sensor of that unit and
    variant rests at, read here — which differs between electrodes (the unit's resting gaps spread) and from the
    nominal unit's; the text names the unit and its serial."""
    import json

    import numpy as np

    from emulator import channels as ch
    from emulator.conversions import ADC_LSB_V
    from emulator.sensor import NoiseSources, Sensor
    from emulator.units import unit

    def reference_noise(args):
        assert main(["noise-budget", "--json", *args]) == 0
        rows = json.loads(capsys.readouterr().out)
        return {r["channel"]: r["pac_bits"] for r in rows if r["source"].endswith(": ADC reference noise")}

    sp17, nominal = reference_noise(["--unit", "17", "--variant", "biotac-sp"]), reference_noise([])
    assert [c for c in sp17 if c.startswith("E")] == [f"E{k}" for k in range(1, 25)]
    assert [c for c in nominal if c.startswith("E")] == [f"E{k}" for k in range(1, 20)]
    p = unit(17).params
    names = [f"E{k}" for k in range(1, 25)]
    rest = Sensor(p, [], names, seed=0, noise=NoiseSources.none(), variant="biotac-sp").analog(
        np.array([ch.channel_index(n) for n in names]), np.full(24, 0.5)) / ADC_LSB_V
    assert [sp17[n] for n in names] == pytest.approx(p.adc_reference_noise_ppm * 1e-6 * np.abs(rest), rel=1e-9)
    assert len({round(sp17[n], 6) for n in names}) > 5 and sp17["E1"] != nominal["E1"]
    assert main(["noise-budget", "--unit", "17", "--variant", "biotac-sp"]) == 0
    assert capsys.readouterr().out.splitlines()[0] == "unit 17 (serial BTU0000000000017), variant biotac-sp"


def test_noise_budget_refuses_an_sp_serial_on_a_biotac_as_every_other_place_does(capsys):
    """`noise-budget --unit BTSP000000000005` (variant biotac by default): a serial a host reads as an SP's on a
    19-electrode sensor is refused in one line naming both flags and the fix (exit 2, nothing printed), as a scene,
    a port and the plugin refuse it; with --variant biotac-sp it is that unit."""
    assert main(["noise-budget", "--unit", "BTSP000000000005"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith('error: --unit BTSP000000000005 --variant biotac: serial "BTSP000000000005" starts "BTSP"')
    assert 'give variant = "biotac-sp", or unit = 5' in err and err.count("\n") == 1
    assert main(["noise-budget", "--unit", "BTSP000000000005", "--variant", "biotac-sp"]) == 0
    assert capsys.readouterr().out.startswith("unit 5 (serial BTSP000000000005), variant biotac-sp\n")


def test_units_compare_prints_each_parameters_difference_from_nominal(capsys):
    """`units --seed 17 --compare`: beside each value the nominal one and the difference (in % where the nominal is
    not zero) and its unit; with --json the nominal values under "nominal"."""
    import json

    assert main(["units", "--seed", "17", "--compare"]) == 0
    lines = [line.split() for line in capsys.readouterr().out.splitlines()[2:]]
    row = next(r for r in lines if r[0] == "resonance_Hz")
    value, nominal, diff = float(row[1]), float(row[2]), float(row[3])
    assert value != nominal and diff == pytest.approx(100 * (value - nominal) / nominal, abs=0.006)
    units = {r[0]: r[-1] for r in lines}  # each row ends with its unit: the parameter's, or a derived figure's
    assert (units["resonance_Hz"], units["inflation_volume_mL"], units["resting_pressure_Pa"]) == ("Hz", "mL", "Pa")
    assert main(["units", "--seed", "17", "--compare", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["nominal"]["resonance_Hz"] == pytest.approx(nominal, rel=1e-5)
    assert doc["parameters"]["resonance_Hz"] == pytest.approx(value, rel=1e-5)


def test_units_compare_says_only_whether_a_seed_differs(capsys):
    """The electrode-gap seed names a draw: `units --compare` printed its numeric difference from the nominal's
    (+5.444e+08), which means nothing; it says "differs" (or "same" for the nominal unit itself)."""
    for argv, said in ((["--seed", "17"], "differs"), ([], "same")):
        assert main(["units", *argv, "--compare"]) == 0
        (row,) = [r.split() for r in capsys.readouterr().out.splitlines() if r.startswith("electrode_gap_seed ")]
        assert row[3] == said, row


def test_params_lists_each_parameter_with_its_unit_range_and_source(capsys):
    """`params` (README): every sensor parameter with its unit, range and source."""
    from emulator.params import PARAMETER_FIELDS

    assert main(["params"]) == 0
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines() if line.strip()}
    for name, f in PARAMETER_FIELDS.items():
        meta = f.metadata
        assert f" {meta['unit']} " in lines[name] and f"({meta['source']})" in lines[name], name
        lo, hi = re.search(r"\[(\S+), (\S+)\]", lines[name]).groups()
        assert (float(lo), float(hi)) == tuple(map(float, meta["range"])), name

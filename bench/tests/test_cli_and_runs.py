"""The CLI end to end: runs write their outputs, bad input gets a clear error, failed runs keep their data."""

import json

import numpy as np
import pytest

from bench.cli import main as cli
from bench.paths import REPO
from bench.reporting.report import write_outputs
from bench.running.runner import run_scene
from bench.scenes.scene import parse_scene
from bench.tests.cli_runs import run_cli

pytestmark = pytest.mark.unit


def test_run_writes_codes_record_report_and_plots(tmp_path, capsys):
    rc = cli.main(["run", str(REPO / "fixtures/scenes/taps.toml"), "--out", str(tmp_path), "--csv", "--quiet"])
    assert rc == 0
    for name in ("codes.npz", "samples.csv", "record.json", "report.md", "traces.png", "spectrogram.png"):
        assert (tmp_path / name).stat().st_size > 0, name
    rec = json.loads((tmp_path / "record.json").read_text())
    assert rec["status"] == "ok" and rec["simulated_s"] == pytest.approx(6.0)
    assert {e["name"] for e in rec["effects"]} >= {"contact_force", "force_coupling", "stage2"}
    assert all(e["seconds"] >= 0 for e in rec["effects"])
    data = np.load(tmp_path / "codes.npz")
    assert data["PAC_code"].size == pytest.approx(6.0 * 2200, abs=1) and data["E7_code"].size == 600
    assert np.all(data["PAC_status"] == 0)
    pa = data["PAC_Pa"]
    assert pa.max() > 50 * 0.37  # the taps are visible well above the noise
    header = (tmp_path / "samples.csv").read_text().splitlines()[0]
    assert header == "time_s,channel,code,status,value,unit"


def test_impact_detection_report_for_the_sphere_scene(tmp_path):
    sc = parse_scene({"scene": {"name": "drops", "duration_s": 3.0, "seed": 4},
                      "analysis": {"impact_detection": True},
                      "stimulus": [{"kind": "sphere_drop", "sphere": "1 mm steel bearing", "at_s": [1.0, 2.0]},
                                   {"kind": "sphere_drop", "sphere": "0.25 mm solder ball", "at_s": [1.5, 2.5]}]})
    rec = write_outputs(run_scene(sc, progress=False), tmp_path, plots=False)
    spheres = rec["impact_detection"]["spheres"]
    assert spheres["1 mm steel bearing"]["detected"] == 2
    assert spheres["0.25 mm solder ball"]["detected"] == 0
    assert [(d["drops"], d["detection_rate"]) for d in spheres.values()] == [(2, 1.0), (2, 0.0)]
    report = (tmp_path / "report.md").read_text()
    assert "| 1 mm steel bearing |" in report and "| 100 % |" in report


def test_a_run_that_fails_part_way_keeps_what_it_recorded(tmp_path, monkeypatch):
    from emulator.sensor import Sensor

    original = Sensor.sample

    def failing(self, channels, times, bus_active=None):
        if np.max(times) > 1.5:
            raise FloatingPointError("simulated failure at 1.5 s")
        return original(self, channels, times, bus_active)

    monkeypatch.setattr(Sensor, "sample", failing)
    sc = parse_scene({"scene": {"name": "f", "duration_s": 4.0}, "host": {"sequence": ["PAC"],
                                                                         "slot_rate_Hz": 2200.0}})
    rec = run_scene(sc, progress=False, chunk_s=0.5)
    record = write_outputs(rec, tmp_path, plots=False)
    assert record["status"] == "failed" and "simulated failure" in record["error"]
    data = np.load(tmp_path / "codes.npz")
    assert data["PAC_code"].size == 1.5 * 2200  # everything before the failure is kept


def test_invalid_scene_gives_a_clear_error_and_no_traceback(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[scene]\nname = "x"\nduration_s = 5\n[[stimulus]]\nkind = "vibration"\nstart_s = 0\n'
                   'duration_s = 1\namplitude_um = 1\nfrequency_Hz = 99999\n')
    out = run_cli("run", bad)
    assert out.returncode == 2
    assert "stimulus[0].frequency_Hz = 99999" in out.stderr and "Traceback" not in out.stderr


def test_help_teaches_the_scene_format():
    out = run_cli("run", "--help")
    assert out.returncode == 0
    for word in ("[[stimulus]]", "sphere_drop", "record.json", "fidelity"):
        assert word in out.stdout


@pytest.mark.parametrize("command", [["scenes"], ["profiles"], ["params"], ["noise-budget"], ["noise-budget", "--json"],
                                     ["validate", str(REPO / "fixtures/scenes/rest.toml")]])
def test_informational_commands_succeed(command, capsys):
    assert cli.main(command) == 0
    assert capsys.readouterr().out.strip()


def test_noise_budget_json_reproduces_table_5_1():
    from emulator.noise_budget import budget

    lines = {x.source: x for x in budget()}
    assert lines["bridge Johnson noise"].rti_uV == pytest.approx(0.29, rel=0.05)
    assert lines["amplifier voltage noise"].rti_uV == pytest.approx(0.39, rel=0.02)
    assert lines["intrinsic total (Table 5-1)"].rti_uV == pytest.approx(0.49, rel=0.03)
    assert lines["total at the ADC output"].pac_bits == pytest.approx(1.4, abs=0.1)


def test_claims_command_prints_json_and_exit_status_follows_the_verdicts(capsys, monkeypatch):
    assert cli.main(["claims", "--only", "scales", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {r["name"] for r in rows} >= {"PDC scale", "PAC scale"} and all(r["passed"] for r in rows)
    # a sensor whose front end has the wrong gain must fail the scale claims, and the command must say so
    from bench.verification import claims
    from emulator.params import SensorParams

    original = claims.Bench

    def miscalibrated(**kw):
        return original(params=SensorParams(stage1_gain=11.0), **kw)

    monkeypatch.setattr(claims, "Bench", miscalibrated)
    assert cli.main(["claims", "--only", "scales"]) == 1
    assert "FAIL" in capsys.readouterr().out


def test_the_command_runs_blas_on_one_thread_unless_the_user_chose():
    """Tiny matrix products: extra BLAS threads only spin (bench/cli/__init__.py); a user's own choice stands."""
    import os
    import subprocess
    import sys

    probe = "import bench.cli.main, os; print(os.environ.get('OPENBLAS_NUM_THREADS'), os.environ.get('OMP_NUM_THREADS'))"
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True).stdout
    assert out.split() == ["1", "1"]
    out = subprocess.run([sys.executable, "-c", probe], env={**env, "OPENBLAS_NUM_THREADS": "4"},
                         capture_output=True, text=True, check=True).stdout
    assert out.split() == ["4", "1"]

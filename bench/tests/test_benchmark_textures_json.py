"""`benchmark --textures --json` prints JSON (it had printed the text table, --json ignored), and --textures and
--effects, each "only" one part, are refused together (both had run --textures alone)."""

import json
from types import SimpleNamespace

import pytest

from bench.cli import main as cli
from bench.verification import benchmark, benchmark_textures as bt

pytestmark = pytest.mark.unit

SLIDING = [{"texture": "3 mm grating", "profile": "fast", "pac_rms_error_bits": 1.0, "spectral_error_dB": 2.0,
            "trial_simulated_s": 6.0, "trial_wall_s": 0.01, "realtime_factor": 600.0}]
DASK = {"trials": 96, "workers_1": {"wall_s": 3.0, "overhead_per_task_s": 1e-3},
        "workers_2": {"wall_s": 2.0, "overhead_per_task_s": 2e-3}, "speedup": 1.5, "mean_task_s": 0.03,
        "estimate_64_workers_trials_per_s": 1600.0}


@pytest.fixture
def quick(monkeypatch):
    monkeypatch.setattr(bt, "sliding_fidelity", lambda say=None: SLIDING)
    monkeypatch.setattr(bt, "dask_scaling", lambda say=None: DASK)
    monkeypatch.setattr(bt, "exploration_speed", lambda: 50000.0)


def test_textures_with_json_prints_json(quick, capsys):
    assert benchmark.main(SimpleNamespace(json=True, textures=True, effects=False)) == 0
    out = json.loads(capsys.readouterr().out)
    assert out == {"sliding": SLIDING, "dask_scaling": DASK, "exploration_steps_per_s": 50000.0}


def test_textures_without_json_prints_the_table(quick, capsys):
    assert benchmark.main(SimpleNamespace(json=False, textures=True, effects=False)) == 0
    out = capsys.readouterr().out
    assert "3 mm grating" in out and "speed-up 1.50×" in out and "50,000 steps/s" in out


def test_textures_and_effects_together_are_refused(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["benchmark", "--textures", "--effects"])
    assert e.value.code == 2 and "not allowed with argument --textures" in capsys.readouterr().err

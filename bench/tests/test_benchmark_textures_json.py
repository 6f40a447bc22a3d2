"""`benchmark --textures --json` prints JSON (it had printed the text table, --json ignored), and --textures and
--effects, each "only" one part, are refused together (both had run --textures alone).  Its sliding rows give every
channel kind's error as the fidelity table measures it (it had compared PAC only)."""

import json
from types import SimpleNamespace

import pytest

from bench.cli import main as cli
from bench.verification import benchmark, benchmark_textures as bt

pytestmark = pytest.mark.unit

SLIDING = [{"texture": "3 mm grating", "profile": "fast",
            "error_bits": {"PAC": 1.0, "PDC": 0.25, "TDC": 0.5, "TAC": 0.0625, "electrodes": 0.125},
            "pac_rms_error_bits": 1.0, "spectral_error_dB": 2.0, "trial_simulated_s": 6.0, "trial_wall_s": 0.01,
            "realtime_factor": 600.0}]
#: the keys of a sliding row (``benchmark --textures --json``): the fidelity table's per-kind errors and PAC's
ROW_KEYS = {"texture", "profile", "error_bits", "pac_rms_error_bits", "spectral_error_dB", "trial_simulated_s",
            "trial_wall_s", "realtime_factor"}
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
    """The sliding table has a column per channel kind (the fidelity table's), each row its errors in bits."""
    assert benchmark.main(SimpleNamespace(json=False, textures=True, effects=False)) == 0
    out = capsys.readouterr().out
    assert "3 mm grating" in out and "speed-up 1.50×" in out and "50,000 steps/s" in out
    lines = out.splitlines()
    header = next(line for line in lines if line.split()[:2] == ["texture", "profile"])
    assert header.split()[2:7] == list(benchmark.ERROR_KIND_COLUMNS.values())
    row = next(line for line in lines if line.strip().startswith("3 mm grating"))
    assert [float(v) for v in row.split()[4:9]] == [SLIDING[0]["error_bits"][k] for k in benchmark.ERROR_KINDS]


def test_the_sliding_table_marks_a_kind_not_measured():
    """A row without a kind's error (a slide read through a frame without TAC, say) prints — there, not 0."""
    row = {**SLIDING[0], "error_bits": {k: v for k, v in SLIDING[0]["error_bits"].items() if k != "TAC"}}
    text = bt.report(measured={"sliding": [row], "dask_scaling": DASK, "exploration_steps_per_s": 1.0})
    fields = next(line for line in text.splitlines() if line.strip().startswith("3 mm grating")).split()
    assert fields[4:9] == ["1.0000", "0.2500", "0.5000", "—", "0.1250"]


def test_the_sliding_rows_give_each_channel_kinds_error_by_the_fidelity_tables_function(monkeypatch):
    """Each texture's rows, one per profile, carry ``error_bits``: every channel kind of the default frame, exactly
    what the fidelity table's ``profile_errors`` measures on the slide's scene (one call per texture, not a second
    error function), PAC's also as ``pac_rms_error_bits``; zero at ``reference``, not at ``fast``.  The rig trial is
    stubbed (its timing is not what this checks)."""
    import math

    calls = []
    real = benchmark.profile_errors

    def spy(scene, profiles):
        calls.append((scene.sequence, scene.channels, real(scene, profiles)))
        return calls[-1][2]

    monkeypatch.setattr(benchmark, "profile_errors", spy)
    monkeypatch.setattr(bt, "run_trial_task", lambda task: {"simulated_s": 6.0})
    rows = bt.sliding_fidelity(textures=(902,))
    assert [(r["texture"], r["profile"]) for r in rows] == [("3 mm grating", p) for p in bt.SLIDING_PROFILES]
    ((sequence, channels, errors),) = calls
    assert sequence == "default" and len(channels) == 23  # PAC, PDC, TDC, TAC and E1..E19
    for r in rows:
        assert set(r) == ROW_KEYS
        assert r["error_bits"] == errors[r["profile"]] and list(r["error_bits"]) == list(benchmark.ERROR_KINDS)
        assert all(math.isfinite(v) and v >= 0.0 for v in r["error_bits"].values())
        assert r["pac_rms_error_bits"] == r["error_bits"]["PAC"]
    by = {r["profile"]: r["error_bits"] for r in rows}
    assert set(by["reference"].values()) == {0.0}
    assert min(by["fast"]["PAC"], by["fast"]["PDC"], by["fast"]["electrodes"]) > 0.0


def test_textures_and_effects_together_are_refused(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["benchmark", "--textures", "--effects"])
    assert e.value.code == 2 and "not allowed with argument --textures" in capsys.readouterr().err

"""Issue 10's per-effect cost table in the benchmark: it runs on a short duration, each row's "with" sensor really
runs its effect and the "without" sensor does not (read from the sensors themselves, not from timings), and the
table reaches the printed and JSON output."""

from __future__ import annotations

import json

import pytest

from bench.verification import benchmark


@pytest.fixture(scope="module")
def costs():
    return benchmark.effect_costs(seconds=2.0, repeats=1, rounds=1)


def _row(costs, marker):
    return [r for r in costs["rows"] if r["marker"] == marker]


def test_every_row_runs_its_effect_with_and_not_without(costs):
    assert len(costs["rows"]) == len(benchmark.EFFECT_ROWS) == 6
    for r in costs["rows"]:
        assert r["marker_with"] != r["marker_without"], r["effect"]
        assert r["with_realtime_factor"] > 0 and r["without_realtime_factor"] > 0


def test_viscoelastic_skin_row_presses_and_creeps(costs):
    (r,) = _row(costs, "skin_creep_ratio")
    assert 0.0 < r["marker_with"] < 1.0  # the standard linear solid: a step gives less than the relaxed pressure
    assert r["marker_without"] == 1.0  # elastic skin
    for name in (r["with"], r["without"]):  # the touches ran: force path and electrodes built and fed
        assert {"contact_force", "force_coupling", "electrodes"} <= set(costs["configs"][name]["effects"])
    assert costs["creep_filter_ms_per_simulated_s"] > 0


def test_noise_hum_unit_and_variant_rows(costs):
    (adc,) = _row(costs, "adc_noise")
    assert adc["marker_with"]["reference_relative"] > 0 and adc["marker_with"]["pac_path_V"] > 0
    assert adc["marker_without"]["reference_relative"] == 0 and adc["marker_without"]["pac_path_V"] == 0
    assert adc["marker_with"]["input_V"] == adc["marker_without"]["input_V"] > 0
    fundamental, off = _row(costs, "mains_hum_Hz")
    assert fundamental["marker_with"] == off["marker_with"] == [60.0, 120.0, 180.0]
    assert fundamental["marker_without"] == [60.0] and off["marker_without"] == []
    (unit,) = _row(costs, "electrode_gap")
    assert unit["marker_with"]["spread_mm"] > 0 and unit["marker_without"]["spread_mm"] == 0
    (sp,) = _row(costs, "variant")
    assert (sp["marker_with"], sp["marker_without"]) == ("biotac-sp", "biotac")
    assert costs["per_slot"]["rest, BioTac SP"]["frame_slots"] == 54
    assert costs["per_slot"]["rest"]["frame_slots"] == 44
    assert costs["configs"]["rest, BioTac SP"]["markers"]["electrodes"] == 24


def test_repeated_presses_cover_the_run():
    presses = benchmark._repeated_presses(45.0)
    assert len(presses) == 3 * 12 and max(p.end_s for p in presses) >= 45.0


def test_table_lines_name_every_effect_and_the_target(costs):
    text = "\n".join(benchmark.effect_cost_lines(costs))
    for r in costs["rows"]:
        assert r["effect"] in text
    assert "target ≥ 1000×: " + ("met" if costs["full_frame"]["met"] else "NOT met") in text
    assert "54-slot frame" in text and "44-slot frame" in text


def test_effects_only_json(capsys):
    """`biotac-bench benchmark --effects --json` (the CLI's flag reaches the table)."""
    from bench.cli import main as cli

    assert cli.main(["benchmark", "--effects", "--json", "--seconds", "1"]) == 0
    doc = json.loads(capsys.readouterr().out)
    rows = doc["effect_costs"]["rows"]
    assert [r["effect"] for r in rows] == [row[0] for row in benchmark.EFFECT_ROWS]
    assert isinstance(doc["effect_costs"]["full_frame"]["met"], bool)


REST_SCENE = '[scene]\nname = "tiny-rest"\nduration_s = 0.5\nseed = 4\n[host]\nsequence = ["PAC"]\nslot_rate_Hz = 2200.0\n'
TAP_SCENE = REST_SCENE.replace("tiny-rest", "tiny-tap") + '[[stimulus]]\nkind = "tap"\nat_s = 0.2\npeak_N = 1.0\n'


def test_the_fidelity_table_compares_noise_free_pac_and_gives_the_other_seeds_floor(tmp_path, monkeypatch):
    """README (what accuracy costs): PAC RMS error compares noise-free analog PAC with the reference profile's — so at
    rest every profile agrees exactly, and a tap shows the coarser profiles' error; the spectral error compares noisy
    runs, and the "reference (other seed)" row, reference against itself with another seed's noise, is its floor
    (above zero: other noise). Two half-second scenes in a folder of their own."""
    from bench.verification import benchmark

    (tmp_path / "rest.toml").write_text(REST_SCENE)
    (tmp_path / "tap.toml").write_text(TAP_SCENE)
    monkeypatch.setattr(benchmark, "SCENES_DIR", tmp_path)
    rows = {(r["scene"], r["profile"]): r for r in benchmark.fidelity_table(progress=lambda m: None)}
    for scene in ("tiny-rest", "tiny-tap"):
        assert [p for s, p in rows if s == scene] == ["fast", "default", "reference", "reference (other seed)"]
        assert (rows[scene, "reference"]["pac_rms_error_bits"], rows[scene, "reference"]["spectral_error_dB"]) == (0, 0)
        floor = rows[scene, "reference (other seed)"]
        assert floor["pac_rms_error_bits"] is None and floor["spectral_error_dB"] > 0.1
    for profile in ("fast", "default"):
        assert rows["tiny-rest", profile]["pac_rms_error_bits"] < 1e-6
        assert rows["tiny-tap", profile]["pac_rms_error_bits"] > 0.1


"""The report's comparison of the pilot's picks with D's, and the strict count of textures beating the baselines."""

from types import SimpleNamespace

import numpy as np

from bench.experiments.experiment import D_BEST_MOVEMENTS, beats_baselines, d_best_movement_ids
from bench.reporting.experiment_report import pilot_pick_comparison, pilot_status
from bench.rigs.texture_rig import movement_grid


def test_d_picks_map_to_their_grid_movements():
    grid = movement_grid()
    for prop, m in d_best_movement_ids().items():
        f, v = D_BEST_MOVEMENTS[prop]
        assert abs(grid[m].force_N / f - 1) < 0.01 and abs(grid[m].velocity_m_per_s / v - 1) < 0.01
    assert d_best_movement_ids() == {"traction": 24, "roughness": 4, "fineness": 14}


def _pilot(u, ran, exclude_high_power=True):
    rows = [{"movement_id": m} for m in ran]
    spec = SimpleNamespace(exclude_high_power=exclude_high_power)
    return SimpleNamespace(spec=spec, pilot_rows=rows, pilot_uncertainty=u,
                           best_movements=np.array([int(np.nanargmin(u[:, k])) for k in range(3)]))


def _kept(result):
    return [m for m, st in pilot_status(result).items() if st == "run"]


def test_d_pick_rank_counts_only_kept_movements():
    u = np.random.default_rng(1).uniform(0.1, 0.9, (36, 3))
    result = _pilot(u, range(36))
    kept = _kept(result)
    assert 0 < len(kept) < 36  # the high-power movements are left out
    row = pilot_pick_comparison(result)["traction"]
    assert row["d_status"] == "run" and row["kept"] == len(kept) and row["d_U"] == u[24, 0]
    assert row["d_rank"] == 1 + sum(u[m, 0] < u[24, 0] for m in kept)
    u[24, 0] = 0.0  # D's traction pick the least uncertain: rank 1
    assert pilot_pick_comparison(_pilot(u, range(36)))["traction"]["d_rank"] == 1


def test_a_d_pick_outside_the_pilot_is_said_so():
    u = np.full((36, 3), np.nan)
    for m, value in ((0, 0.3), (7, 0.4), (14, 0.2)):
        u[m] = value
    cmp = pilot_pick_comparison(_pilot(u, (0, 7, 14)))
    assert cmp["traction"]["d_status"] == "not-run" and cmp["traction"]["d_U"] is None
    assert cmp["fineness"]["d_status"] == "run" and cmp["fineness"]["d_rank"] == 1


def _identification(per_strategy):
    """summary()-shaped results: strategy -> {texture: (accuracy, median moves)}."""
    out = {}
    for strat, per_tex in per_strategy.items():
        out[strat] = [SimpleNamespace(true_texture=t, correct=np.array([1.0] * round(100 * a) + [0.0] * (100 - round(100 * a))),
                                      n_moves=np.full(100, m), decided=np.array([t])) for t, (a, m) in per_tex.items()]
    return out


def test_ties_count_as_not_worse_but_not_as_strictly_better(monkeypatch):
    from bench.experiments import experiment

    stats = {"bayesian": {1: (1.0, 2), 2: (0.9, 2), 3: (1.0, 1)},
             "cycle": {1: (1.0, 2), 2: (0.8, 2), 3: (1.0, 2)},
             "random": {1: (1.0, 2), 2: (0.8, 3), 3: (0.9, 2)}}

    def fake_summary(result):
        return {f"identification/{s}": {"per_texture_accuracy": {t: a for t, (a, _) in v.items()},
                                        "per_texture_median_moves": {t: float(m) for t, (_, m) in v.items()}}
                for s, v in stats.items()}

    monkeypatch.setattr(experiment, "summary", fake_summary)
    assert beats_baselines(None) == 3  # texture 1 ties both: not worse
    assert beats_baselines(None, strict=True) == 2  # ... but not strictly better


def test_nearest_neighbour_sigma_finds_the_closest_other_texture():
    from bench.experiments.pairs import nearest_neighbour_sigma

    mean = np.zeros((3, 2, 3))
    mean[1, 0, 0] = 2.0  # texture 20 differs from 10 by 2 σ in one property and movement
    mean[2, 1, 2] = 5.0  # texture 30 by 5 σ
    model = SimpleNamespace(textures=np.array([10, 20, 30]), mean=mean, sigma=np.ones((3, 2, 3)),
                            texture_index=lambda ids: np.searchsorted([10, 20, 30], ids))
    out = nearest_neighbour_sigma(model, [10, 30])
    assert out[10] == (2.0, 20)
    assert out[30][1] in (10, 20) and abs(out[30][0] - 5.0) < 1e-12


def test_most_confused_pairs_are_the_pairs_the_model_confuses_most():
    """Four glass textures: T24 and T25 one mean apart by 0.01 σ, T26 and T27 by 0.5 σ, the two couples 5 σ apart.
    "most-confused" pairs the first couple, then the second (a mutation hunt: a reversed sort picked the least
    confused pairs, T24–T27 and T25–T26, and no test noticed)."""

    from bench.experiments import exploration as ex
    from bench.experiments.experiment import _pick_pairs

    means = np.array([0.0, 0.01, 5.0, 5.5])[:, None, None] * np.ones((4, 3, 3))
    model = ex.TextureModel(np.array([24, 25, 26, 27]), np.array([0, 1, 2]), means, np.ones((4, 3, 3)),
                            np.full((4, 3, 3), 5))
    assert _pick_pairs(model, np.array([0, 1, 2]), 2, "most-confused", seed=0) == [(24, 25), (26, 27)]


def test_most_confused_reads_each_property_at_its_own_best_movement():
    """Traction's best movement (0) cannot tell T24, T25 and T26 apart; roughness's and fineness's (1 and 2) cannot
    tell T26 from T27.  Averaged over the properties, each at its own movement, T26–T27 is the most confused pair
    (2 of 3 properties); read all at traction's movement, T24–T25 would be."""
    from bench.experiments import exploration as ex
    from bench.experiments.experiment import _pick_pairs

    means = np.zeros((4, 3, 3))
    means[:, 0, :] = np.array([0.0, 0.0, 0.0, 9.0])[:, None]  # movement 0: T24 = T25 = T26, T27 far
    means[:, 1:, :] = np.array([0.0, 9.0, 20.0, 20.0])[:, None, None]  # movements 1, 2: T26 = T27
    model = ex.TextureModel(np.array([24, 25, 26, 27]), np.array([0, 1, 2]), means, np.ones((4, 3, 3)),
                            np.full((4, 3, 3), 5))
    assert _pick_pairs(model, np.array([0, 1, 2]), 1, "most-confused", seed=0) == [(26, 27)]


def test_the_skin_policy_says_never_replaced_when_replacement_is_off():
    """summary.json's skin_wear states the replacement level only when the experiment replaces skins: with
    replace_skin off it is null (the report then says "never replaced"), whatever replace_at holds."""
    from bench.reporting.experiment_report import _skin_wear

    on = _skin_wear(SimpleNamespace(wear=True, replace_skin=True, replace_at=0.2))
    off = _skin_wear(SimpleNamespace(wear=True, replace_skin=False, replace_at=0.2))
    assert (on["replace_at"], off["replace_at"]) == (0.2, None)

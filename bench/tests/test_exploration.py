"""Bayesian exploration (D ch. 6): D's formulas, the pilot stage, strategies and virtual exploration on synthetic
textures with known answers."""

import dataclasses
import math

import numpy as np
import pytest
from scipy import integrate

from bench.experiments import exploration as ex

pytestmark = pytest.mark.unit


def tables(mu, sigma, n_train=5, n_valid=5, seed=0):
    """(training, validation) tables drawn from normals mu, sigma of shape (T, M, 3); texture ids 1…T."""
    rng = np.random.default_rng(seed)
    mu, sigma = np.broadcast_arrays(np.asarray(mu, float), np.asarray(sigma, float))
    T, M, P = mu.shape
    out = []
    for n in (n_train, n_valid):
        t, m, p, k = np.meshgrid(np.arange(T), np.arange(M), np.arange(P), np.arange(n), indexing="ij")
        v = mu[..., None] + sigma[..., None] * rng.standard_normal(t.shape)
        out.append(ex.TrialTable(t.ravel() + 1, m.ravel(), p.ravel(), k.ravel(), v.ravel()))
    return out


def model_from(mu, sigma):
    mu, sigma = np.broadcast_arrays(np.asarray(mu, float), np.asarray(sigma, float))
    T, M, _ = mu.shape
    return ex.TextureModel(np.arange(1, T + 1), np.arange(M), mu.copy(), sigma.copy(), np.full(mu.shape, 5))


# ------------------------------------------------------------------------------------------------ formulas


def test_bhattacharyya_is_one_for_identical_normals():
    assert ex.bhattacharyya(0.3, 0.1, 0.3, 0.1) == pytest.approx(1.0, abs=1e-15)
    assert np.allclose(ex.bhattacharyya([1.0, -2.0, 7.0], [0.01, 1.0, 30.0], [1.0, -2.0, 7.0],
                                        [0.01, 1.0, 30.0]), 1.0)


@pytest.mark.parametrize("m1, s1, m2, s2", [(0, 1, 1, 1), (0, 1, 0, 3), (2, 0.5, -1, 2), (0, 0.2, 0.9, 0.1),
                                            (5, 1, 5.1, 0.05)])
def test_sensor_md_formula_is_the_bhattacharyya_integral(m1, s1, m2, s2):
    def pdf(x, m, s):
        return math.exp(-0.5 * ((x - m) / s) ** 2) / (s * math.sqrt(2 * math.pi))
    lo, hi = min(m1 - 12 * s1, m2 - 12 * s2), max(m1 + 12 * s1, m2 + 12 * s2)
    bc, _ = integrate.quad(lambda x: math.sqrt(pdf(x, m1, s1) * pdf(x, m2, s2)), lo, hi, points=[m1, m2],
                           limit=200, epsabs=1e-13)
    assert ex.bhattacharyya(m1, s1, m2, s2) == pytest.approx(bc, rel=1e-7, abs=1e-12)
    assert ex.bhattacharyya(m1, s1, m2, s2) == pytest.approx(ex.bhattacharyya(m2, s2, m1, s1), rel=1e-15)


def test_expected_uncertainty_reduces_from_eqs_6_8_and_6_9():
    rng = np.random.default_rng(4)
    T, Q = 6, 5
    mu, s = rng.normal(size=(T, Q)), rng.uniform(0.2, 1.0, (T, Q))
    c = ex.bhattacharyya(mu[:, None], s[:, None], mu[None], s[None])
    prior = rng.dirichlet(np.ones(T))
    direct = np.zeros(Q)
    for q in range(Q):  # u_i = Σ_{j≠i} C_ij P_j / Σ_j C_ij P_j (6.8);  U = Σ_i u_i P_i (6.9)
        for i in range(T):
            num = sum(c[i, j, q] * prior[j] for j in range(T) if j != i)
            den = sum(c[i, j, q] * prior[j] for j in range(T))
            direct[q] += num / den * prior[i]
    assert np.allclose(ex.expected_uncertainty(c, prior), direct, rtol=1e-12)
    # limits: T identical textures leave 1 − 1/T; T textures that never overlap leave 0
    assert ex.expected_uncertainty(np.ones((4, 4, 1)), np.ones(4)) == pytest.approx(0.75)
    assert ex.expected_uncertainty(np.eye(4)[:, :, None], np.ones(4)) == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_batched_uncertainty_matches_the_formula_and_is_independent_of_batching(backend):
    rng = np.random.default_rng(5)
    T, Q = 30, 12
    mu, s = rng.normal(size=(T, Q)), rng.uniform(0.05, 0.5, (T, Q))
    c = np.ascontiguousarray(ex.bhattacharyya(mu[:, None], s[:, None], mu[None], s[None]))
    post = rng.dirichlet(np.full(T, 0.1), size=25)
    u = ex.uncertainty_rows(c, post, prune=0.0, backend=backend)
    assert np.allclose(u, [ex.expected_uncertainty(c, p) for p in post], rtol=1e-12, atol=1e-14)
    pruned = ex.uncertainty_rows(c, post, prune=1e-6, backend=backend)
    dropped = np.where(post <= 1e-6, post, 0).sum(axis=1)
    assert np.all(np.abs(pruned - u) <= 2 * dropped[:, None] + 1e-15)
    pieces = np.concatenate([ex.uncertainty_rows(c, post[i:i + 4], 1e-6, backend) for i in range(0, 25, 4)])
    assert np.array_equal(pieces, pruned)
    other = "numpy" if backend == "numba" else "numba"
    assert np.allclose(ex.uncertainty_rows(c, post, 1e-6, other), pruned, rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_candidates_at_the_pruning_threshold_are_left_out_and_a_row_with_none_left_is_fully_uncertain(backend):
    """Only candidates with posterior > prune enter U: with prune = 0 (the exact formula), a candidate at posterior 0
    that overlaps no other (C_ij = 0 for j ≠ i) adds no 0/0 term, and U is that of the two others (two identical
    textures: 1/2); a row whose every candidate is at or below the threshold has no term: U = 1."""
    c = np.zeros((3, 3, 1))
    c[:2, :2], c[2, 2] = 1.0, 1.0
    u = ex.uncertainty_rows(c, np.array([[0.5, 0.5, 0.0]]), prune=0.0, backend=backend)
    assert u[0, 0] == pytest.approx(0.5)
    assert ex.uncertainty_rows(c, np.full((1, 3), 1e-13), prune=1e-12, backend=backend)[0, 0] == 1.0


def test_posterior_update_is_bayes_rule_and_sums_to_one():
    prior = np.array([0.5, 0.3, 0.2, 0.0])
    mean, sigma = np.array([0.0, 1.0, 2.0, 0.5]), np.array([1.0, 0.5, 2.0, 1.0])
    post = ex.update_posterior(prior, mean, sigma, 0.8)
    like = np.exp(-0.5 * ((0.8 - mean) / sigma) ** 2) / sigma
    assert np.allclose(post, prior * like / np.sum(prior * like), rtol=1e-12)
    assert post.sum() == pytest.approx(1.0, abs=1e-15) and post[3] == 0.0
    far = ex.update_posterior(np.full((2, 3), 1 / 3), np.array([0.0, 1.0, 2.0]), np.ones(3), np.array([1e3, -1e3]))
    assert np.all(np.isfinite(far)) and np.allclose(far.sum(axis=1), 1.0)
    assert far[0].argmax() == 2 and far[1].argmax() == 0


def test_benefit_alpha_is_one_over_uses_and_penalises_repeats():
    u = np.array([0.0, 0.3, 0.81, 1.0])
    assert np.allclose(ex.benefit(u, 0), 1 - u)           # first use: α = 1
    assert np.allclose(ex.benefit(u, 1), 1 - np.sqrt(u))  # second: α = 1/2
    assert np.allclose(ex.benefit(u, 2), 1 - np.cbrt(u))
    assert np.all(ex.benefit(u[1:3], 1) < ex.benefit(u[1:3], 0))


def test_benefit_takes_an_uncertainty_rounded_past_0_or_1_as_0_or_1():
    """U = 1 − Σ P_i²/Σ_j C_ij P_j can round a hair below 0 (one certain candidate) or above 1: the benefit is then
    that of U = 0 (1) or U = 1 (0), never NaN from a fractional power of a negative number."""
    assert np.array_equal(ex.benefit(np.array([-1e-16, 1.0 + 1e-15]), 2), [1.0, 0.0])


# ------------------------------------------------------------------------------------------------ table and model


def test_fit_model_mean_and_sample_sigma():
    tab = ex.TrialTable(texture=[3, 3, 3, 3, 7, 7], movement=[0, 0, 0, 0, 0, 0], prop=[0, 0, 0, 0, 0, 0],
                        trial=[0, 1, 2, 3, 0, 1], value=[1.0, 2.0, 3.0, 4.0, 5.0, 5.0])
    tab = ex.TrialTable.concat([tab] + [ex.TrialTable(tab.texture, tab.movement, tab.prop + p, tab.trial,
                                                      tab.value) for p in (1, 2)])
    m = ex.fit_model(tab, sigma_floor=1e-9, sigma_floor_rel=0.0)
    assert list(m.textures) == [3, 7] and list(m.movements) == [0]
    assert m.mean[:, 0, 0] == pytest.approx([2.5, 5.0])
    assert m.sigma[0, 0, 0] == pytest.approx(np.std([1, 2, 3, 4], ddof=1))
    assert m.sigma[1, 0, 0] == 1e-9  # identical trials: the floor, never 0
    rel = ex.fit_model(tab, sigma_floor=1e-9, sigma_floor_rel=0.1)
    assert rel.sigma[1, 0, 0] == pytest.approx(0.1 * np.std([2.5, 5.0]))  # 10 % of the spread of the means
    assert list(m.n_trials[:, 0, 0]) == [4, 2]


def test_from_wide_and_select():
    tab = ex.TrialTable.from_wide(texture=[1, 1, 2], movement=[0, 0, 0], trial=[0, 1, 0], traction=[0.1, 0.2, 0.3],
                                  roughness=[1.0, 2.0, 3.0], fineness=[5.0, 6.0, 7.0])
    assert len(tab) == 9
    r = tab.select(textures=[1], props=[ex.ROUGHNESS])
    assert list(r.value) == [1.0, 2.0] and list(r.trial) == [0, 1]


@pytest.mark.parametrize("kwargs, message", [
    (dict(texture=[1, 1], movement=[0, 0], prop=[0, 0], trial=[0, 0], value=[1.0, 2.0]), "duplicate"),
    (dict(texture=[1], movement=[0], prop=[3], trial=[0], value=[1.0]), "prop ids are 0..2"),
    (dict(texture=[1, 2], movement=[0], prop=[0, 0], trial=[0, 0], value=[1.0, 2.0]), "movement has 1 rows"),
    (dict(texture=[1], movement=[0], prop=[0], trial=[0], value=[np.nan]), "NaN"),
    (dict(texture=[-1], movement=[0], prop=[0], trial=[0], value=[1.0]), "texture ids must be >= 0"),
    (dict(texture=[1.5], movement=[0], prop=[0], trial=[0], value=[1.0]), "texture must hold integers"),
])
def test_trial_table_rejects_malformed_input(kwargs, message):
    with pytest.raises(ex.ExplorationError, match=message):
        ex.TrialTable(**kwargs)


def test_incomplete_table_is_named():
    tab = ex.TrialTable(texture=[1, 1, 1, 2, 2], movement=[0, 0, 0, 0, 0], prop=[0, 1, 2, 0, 1],
                        trial=[0, 0, 0, 0, 0], value=[1.0, 2, 3, 4, 5])
    with pytest.raises(ex.ExplorationError, match="texture 2 movement 0 fineness"):
        ex.fit_model(tab)


# ------------------------------------------------------------------------------------------------ pilot


def pilot_case():
    """10 textures, 4 movements: movement 2 best for traction, 0 for roughness, 1 for fineness; 3 good at all."""
    rng = np.random.default_rng(8)
    mu = rng.uniform(0, 1, (10, 1, 3)) * np.ones((1, 4, 1))
    sigma = np.full((10, 4, 3), 0.3)
    sigma[:, 2, 0] = sigma[:, 0, 1] = sigma[:, 1, 2] = 0.02
    sigma[:, 3, :] = 0.01
    return model_from(mu, sigma)


def test_pilot_picks_least_uncertain_movement_per_property_and_honours_exclusions():
    m = pilot_case()
    u = ex.pilot_uncertainty(m)
    assert u.shape == (4, 3) and np.all((u >= 0) & (u < 1))
    assert list(ex.least_uncertain_movements(m)) == [3, 3, 3]
    assert list(ex.least_uncertain_movements(m, exclude_movements=[3])) == [2, 0, 1]
    assert np.all(np.isnan(ex.pilot_uncertainty(m, exclude_movements=[3])[3]))
    sub = ex.pilot_uncertainty(m, textures=[1, 2])  # equal priors over two textures only
    assert sub[0, 0] == pytest.approx(ex.expected_uncertainty(m.confusion([1, 2])[:, :, 0, 0], [1, 1]))


def test_movement_grid_is_ds_geometric_series():
    g = ex.movement_grid()
    assert g["movement"].size == 36
    assert g["force_N"].min() == pytest.approx(0.2) and g["force_N"].max() == pytest.approx(2.0)
    assert g["velocity_m_s"].min() == pytest.approx(0.01) and g["velocity_m_s"].max() == pytest.approx(0.1)
    picks = [(1.26, 0.01), (0.2, 0.0631), (0.5, 0.025)]  # D's best: traction, roughness, fineness
    for f, v in picks:
        i = np.flatnonzero(np.isclose(g["force_N"], f, rtol=0.01) & np.isclose(g["velocity_m_s"], v, rtol=0.01))
        assert i.size == 1 and not g["high_power"][i[0]]
    worn = np.isclose(g["force_N"], 1.26, rtol=0.01) & np.isclose(g["velocity_m_s"], 0.0631, rtol=0.01)
    assert g["high_power"][worn].all() and g["high_power"].sum() == 15


# ------------------------------------------------------------------------------------------------ strategies


def test_alpha_sends_the_next_choice_elsewhere_after_a_use():
    # two textures; traction at movement 0 gives U = 0.3, at movement 1 U = 0.4; everything else is useless (U = 0.5)
    def gap(u):  # C = U / (1 − U) for two equiprobable textures; C = exp(−d²/8σ²) for equal σ = 1
        return math.sqrt(-8.0 * math.log(u / (1 - u)))
    mu = np.zeros((2, 2, 3))
    mu[1, 0, 0], mu[1, 1, 0] = gap(0.3), gap(0.4)
    ctx = ex.prepare(model_from(mu, 1.0))
    assert ex.pilot_uncertainty(ctx.model)[:, 0] == pytest.approx([0.3, 0.4])
    post = np.full((1, 2), 0.5)
    made = np.zeros((1, 2, 3), np.int64)
    bayes = ex.STRATEGIES["bayesian"]
    assert bayes(ctx, ex.ExplorationState(post, made, 0), np.array([0.5]))[0] == 0 * 3 + 0
    made[0, 0, 0] = 1  # after one use: B0 = 1 − √0.3 = 0.45 < B1 = 0.6
    assert bayes(ctx, ex.ExplorationState(post, made, 1), np.array([0.5]))[0] == 1 * 3 + 0
    made[0, 0, 0], made[0, 0, 2] = 0, 1  # the movement was made (for fineness): still a repeat (D counts movements)
    assert bayes(ctx, ex.ExplorationState(post, made, 1), np.array([0.5]))[0] == 1 * 3 + 0
    by_combo = ex.make_bayesian("combination")
    assert by_combo(ctx, ex.ExplorationState(post, made, 1), np.array([0.5]))[0] == 0


def test_the_trial_drawn_does_not_depend_on_the_movement_chosen():
    """Each step draws its choice and its validation trial from separate uniforms (sim_uniforms: [choice, trial,
    tie-break]): with the random strategy over 4 movements × 3 properties and 5 validation trials, the trial drawn at
    the first step is uncorrelated with the choice (|r| < 0.1 over 2000 simulations), and each trial is drawn about
    equally often."""
    train, valid = tables(np.zeros((2, 4, 3)), 1.0)
    r = ex.simulate(ex.fit_model(train), valid, 1, strategy="random", max_moves=1, n_sims=2000, seed=4)
    choice = (r.movement[:, 0] * 3 + r.prop[:, 0]).astype(float)
    assert abs(np.corrcoef(choice, r.trial[:, 0])[0, 1]) < 0.1
    assert np.all(np.abs(np.bincount(r.trial[:, 0], minlength=5) / 2000 - 0.2) < 0.04)


def test_validation_trials_of_movements_the_model_lacks_are_ignored():
    """A validation table may hold movements the training did not (an excluded movement): the simulation draws from
    the model's movements only, exactly as if those rows were absent."""
    train, valid = tables(np.arange(24.0).reshape(2, 4, 3), 1.0)
    extra = ex.TrialTable(valid.texture, valid.movement + 10, valid.prop, valid.trial, valid.value)
    model = ex.fit_model(train)
    a = ex.simulate(model, valid, 1, n_sims=20, seed=3)
    b = ex.simulate(model, ex.TrialTable.concat([valid, extra]), 1, n_sims=20, seed=3)
    assert np.array_equal(a.trial, b.trial) and np.array_equal(a.value, b.value, equal_nan=True)


def test_cycle_and_random_strategies():
    ctx = ex.prepare(pilot_case(), exclude_movements=[3])
    state = ex.ExplorationState(np.full((4, 10), 0.1), np.zeros((4, 4, 3), np.int64), 0)
    seq = [ex.cycle(ctx, ex.ExplorationState(state.posterior, state.made, k), np.zeros(4))[0] for k in range(4)]
    assert [divmod(q, 3) for q in seq] == [(2, 0), (0, 1), (1, 2), (2, 0)]
    u = np.random.default_rng(0).random(12000)
    q = ex.random_choice(ctx, state, u)
    counts = np.bincount(q, minlength=12)
    assert q.min() >= 0 and q.max() <= 11 and counts.min() > 850 and counts.max() < 1150


# ------------------------------------------------------------------------------------------------ simulation


def separated_case(T=20, M=4, seed=1):
    rng = np.random.default_rng(seed)
    mu = rng.permuted(np.tile(np.arange(T, dtype=float)[:, None, None], (1, M, 3)), axis=0)
    return tables(mu, 0.05, seed=seed)


def test_well_separated_textures_are_identified_in_one_or_two_moves():
    train, valid = separated_case()
    model = ex.fit_model(train)
    results = [ex.simulate(model, valid, t, n_sims=20, seed=3) for t in model.textures]
    assert ex.accuracy(results) >= 0.99
    n = np.concatenate([r.n_moves for r in results])
    assert np.all(n <= 2) and ex.median_moves(results) == 1
    assert all(r.converged.all() for r in results)


def test_identical_textures_are_a_coin_toss_and_hit_the_move_limit():
    rng = np.random.default_rng(2)
    mu = rng.normal(size=(1, 4, 3))
    train, valid = tables(np.repeat(mu, 2, axis=0), 0.1, seed=2)
    one = train.texture == 1  # texture 2's training trials: copies of texture 1's
    same = ex.TrialTable.concat([train.select(textures=[1]),
                                 ex.TrialTable(np.full(one.sum(), 2), train.movement[one], train.prop[one],
                                               train.trial[one], train.value[one])])
    model = ex.fit_model(same)
    assert np.array_equal(model.mean[0], model.mean[1]) and np.array_equal(model.sigma[0], model.sigma[1])
    results = [ex.simulate(model, valid, t, n_sims=300, seed=11) for t in (1, 2)]
    for r in results:
        assert np.all(r.n_moves == 10) and not r.converged.any()
        assert np.allclose(r.posterior[:, -1], 0.5)
        assert 0.4 < r.correct.mean() < 0.6
        # α = 1/n spreads the 10 moves over the 4 movements: counts differ by at most one
        counts = np.stack([(r.movement == m).sum(axis=1) for m in range(4)], axis=1)
        assert np.all(counts.max(axis=1) - counts.min(axis=1) <= 1)
    assert ex.median_moves(results) == math.inf and ex.median_moves(results, "limit") == 10
    assert 0.45 < ex.accuracy(results) < 0.55


def informative_case():
    """10 textures, 12 movements: only traction at movement 5 tells them apart."""
    T, M = 10, 12
    mu = np.zeros((T, M, 3))
    mu[:, 5, 0] = np.arange(T) * 1.0
    return tables(mu, 0.1, seed=6)


def test_bayesian_beats_random_when_one_movement_is_informative():
    train, valid = informative_case()
    model = ex.fit_model(train)
    ctx = ex.prepare(model)
    run = {s: [ex.simulate(model, valid, t, strategy=s, n_sims=40, seed=5, context=ctx) for t in model.textures]
           for s in ("bayesian", "random")}
    assert ex.accuracy(run["bayesian"]) >= 0.97
    assert np.all(np.concatenate([r.movement[:, 0] for r in run["bayesian"]]) == 5)
    assert np.all(np.concatenate([r.prop[:, 0] for r in run["bayesian"]]) == ex.TRACTION)
    assert ex.accuracy(run["random"]) < 0.6
    assert ex.median_moves(run["bayesian"]) < ex.median_moves(run["random"], "limit")


def test_results_do_not_depend_on_chunking_order_or_backend():
    rng = np.random.default_rng(9)
    mu = rng.normal(size=(40, 6, 3))
    train, valid = tables(mu, rng.uniform(0.1, 0.6, (40, 6, 3)), seed=9)
    model = ex.fit_model(train)
    whole = ex.simulate(model, valid, 17, strategy="bayesian", n_sims=30, seed=123)
    parts = [ex.simulate(model, valid, 17, strategy="bayesian", n_sims=n, seed=123, first_sim=a)
             for a, n in [(20, 10), (0, 7), (7, 13)]]
    joined = ex.ExplorationResult.concat(parts)
    slow = ex.simulate(model, valid, 17, strategy="bayesian", n_sims=30, seed=123, backend="numpy")
    for other in (joined, slow):
        for k in ex.ExplorationResult._PER_SIM:
            assert np.array_equal(getattr(whole, k), getattr(other, k), equal_nan=k in ("value", "posterior")), k
    assert whole.n_moves.min() >= 1 and len(np.unique(whole.n_moves)) > 1  # a non-trivial case
    again = ex.simulate(model, valid, 17, n_sims=30, seed=124)
    assert not np.array_equal(again.trial, whole.trial)


def test_result_records_the_exploration():
    train, valid = informative_case()
    model = ex.fit_model(train)
    r = ex.simulate(model, valid, 4, strategy="random", n_sims=50, seed=1)
    assert r.posterior.shape == (50, 11, 10) and r.movement.shape == (50, 10)
    for s in range(50):
        n = r.n_moves[s]
        assert np.allclose(r.posterior[s, : n + 1].sum(axis=1), 1.0)
        assert np.all(np.isnan(r.posterior[s, n + 1:])) and np.all(r.movement[s, n:] == -1)
        assert np.all(np.isin(r.trial[s, :n], np.arange(5)))
        # each value is the drawn validation trial of the true texture at that movement and property
        for k in range(n):
            row = valid.select(textures=[4], movements=[r.movement[s, k]], props=[r.prop[s, k]])
            assert r.value[s, k] == row.value[row.trial == r.trial[s, k]][0]
        assert r.converged[s] == (r.posterior[s, n].max() > 0.99)
        assert r.converged[s] or n == 10  # stops only past the threshold or at the limit …
        assert np.all(r.posterior[s, :n].max(axis=1) <= 0.99)  # … and not before
        assert r.decided[s] == r.candidates[np.argmax(r.posterior[s, n])]


def test_pairs_use_the_pair_threshold_and_exclude_other_textures():
    train, valid = separated_case()
    model = ex.fit_model(train)
    r = ex.simulate(model, valid, 3, candidates=[3, 9], n_sims=10, seed=0)
    assert r.threshold == ex.PAIR_THRESHOLD and r.posterior.shape[2] == 2 and r.correct.all()
    assert ex.simulate(model, valid, 3, n_sims=1).threshold == ex.ABSOLUTE_THRESHOLD


def test_simulation_input_errors():
    train, valid = separated_case()
    model = ex.fit_model(train)
    with pytest.raises(ex.ExplorationError, match="unknown texture id"):
        ex.simulate(model, valid, 3, candidates=[3, 99], n_sims=1)
    holed = ex.TrialTable.concat([valid.select(movements=[0, 1, 3]), valid.select(movements=[2], props=[0, 2])])
    with pytest.raises(ex.ExplorationError, match="no trials of texture 3 at movement 2 roughness"):
        ex.simulate(model, holed, 3, n_sims=1)


def test_summaries():
    train, valid = separated_case(T=5)
    model = ex.fit_model(train)
    results = [ex.simulate(model, valid, t, n_sims=4, seed=0) for t in model.textures]
    labels, counts = ex.confusion_matrix(results)
    assert list(labels) == [1, 2, 3, 4, 5] and np.array_equal(counts, 4 * np.eye(5, dtype=int))
    decided = np.array([2, 2, 1, 1])
    fake = dataclasses.replace(results[0], decided=decided, correct=decided == 1)
    labels, counts = ex.confusion_matrix(fake, labels=[1, 2, 3])
    assert counts[0].tolist() == [2, 2, 0] and ex.accuracy(fake) == 0.5
    none = ex.simulate(model, valid, 1, n_sims=0)  # no simulation: the accuracy is undefined, not 0 %
    assert np.isnan(ex.accuracy(none)) and np.isnan(ex.median_moves(none))


def test_spread_check_sees_a_shift_of_the_validation_trials_and_nothing_else():
    """Validation trials drawn like the training trials sit as far from the training normals as training trials
    from their leave-one-out normals (ratio near 1); shifting one property by 3 σ raises only its ratio."""
    T = 40
    means = np.random.default_rng(1).normal(size=(T, 3)) * 10

    def draw(seed, roughness_shift):
        tex, trial = np.repeat(np.arange(T), 5), np.tile(np.arange(5), T)
        v = means[tex] + np.random.default_rng(seed).normal(size=(tex.size, 3)) + [0.0, roughness_shift, 0.0]
        return ex.TrialTable.from_wide(tex, np.zeros_like(tex), trial, v[:, 0], v[:, 1], v[:, 2])

    same = ex.spread_check(draw(2, 0.0), draw(3, 0.0))
    assert all(0.7 < same[p]["ratio"] < 1.4 for p in ex.PROPERTIES)
    assert 0.6 < same["all"]["leave_one_out_median_abs_z"] < 1.1  # iid normals, 4 trials per held-out fit
    shifted = ex.spread_check(draw(2, 0.0), draw(3, 3.0))
    assert shifted["roughness"]["ratio"] > 3.0
    assert shifted["traction"] == same["traction"] and shifted["fineness"] == same["fineness"]


# --- from a mutation hunt: two trials per cell, the stopping rule, even medians, per-texture draws ------------------
def _two_trial_table(a=5.0, b=6.0):
    tab = ex.TrialTable(texture=[3, 3, 7, 7], movement=[0] * 4, prop=[0] * 4, trial=[0, 1, 0, 1],
                        value=[1.0, 2.0, a, b])
    return ex.TrialTable.concat([ex.TrialTable(tab.texture, tab.movement, tab.prop + p, tab.trial, tab.value)
                                 for p in (0, 1, 2)])


def test_two_trials_give_the_sample_sigma_not_the_floor():
    """D's training had 5 trials; the fewer-trials ablation has 2: σ = |a − b|/√2, the n − 1 sample deviation."""
    m = ex.fit_model(_two_trial_table(), sigma_floor=1e-9, sigma_floor_rel=0.0)
    assert m.sigma[:, 0, 0] == pytest.approx([1 / math.sqrt(2)] * 2, rel=1e-12)


def test_spread_check_with_two_training_trials_skips_leave_one_out_and_stays_finite():
    train = _two_trial_table()
    check = ex.spread_check(train, train, sigma_floor=1e-9, sigma_floor_rel=0.0)
    assert check["all"]["n_training"] == 0 and math.isfinite(check["all"]["validation_median_abs_z"])


def test_a_simulation_stops_exactly_when_a_candidate_passes_the_threshold():
    """Two textures 1 σ apart in every cell: the posterior climbs over several movements, so some simulations pass
    99 % before 99.9 %.  Each stops at the first step whose maximum exceeds the pair threshold (0.999), and not
    before: every earlier step's maximum is at most 0.999; one stopped short of the move limit has converged."""
    mu = np.zeros((2, 2, 3))
    mu[1] += 1.0
    train, valid = tables(mu, 1.0, n_train=30, n_valid=30, seed=3)
    r = ex.simulate(ex.fit_model(train), valid, 1, candidates=[1, 2], n_sims=300, seed=5, max_moves=40)
    assert r.threshold == 0.999
    before = [r.posterior[s, : r.n_moves[s]].max() for s in range(len(r))]
    after = np.array([r.posterior[s, r.n_moves[s]].max() for s in range(len(r))])
    assert max(before) <= 0.999
    assert np.all(r.converged[r.n_moves < 40]) and np.all(after[r.converged] > 0.999)
    assert max(before) > 0.99  # some passed 99 % and went on: the case tells the two thresholds apart


def test_median_moves_of_an_even_count_is_the_mean_of_the_middle_two():
    train, valid = separated_case(T=5)
    r = ex.simulate(ex.fit_model(train), valid, 1, n_sims=4, seed=0)
    four = dataclasses.replace(r, n_moves=np.array([1, 2, 3, 4]), converged=np.array([True, True, True, False]))
    assert ex.median_moves(dataclasses.replace(four, converged=np.ones(4, bool))) == 2.5
    assert ex.median_moves(four, unconverged="exclude") == 2.0  # the unconverged 4 left out: 1, 2, 3
    assert ex.median_moves(four, unconverged="limit") == 2.5
    assert ex.median_moves(four) == 2.5  # counted as infinite: (2 + 3) / 2


def test_each_true_texture_draws_its_own_random_numbers():
    sims = np.arange(5)
    assert not np.array_equal(ex.sim_uniforms(7, 3, sims, 10), ex.sim_uniforms(7, 4, sims, 10))
    assert np.array_equal(ex.sim_uniforms(7, 3, sims, 10), ex.sim_uniforms(7, 3, sims, 10))


def test_confusion_csv_has_a_row_per_true_texture_and_a_column_per_decision():
    """confusion.csv (experiment_report.confusion_rows): texture 1's four simulations decided 2, 2, 1 and 3, texture
    2's all 2 — the rows are the true textures, the columns the decisions (texture 3, decided but never true, gets a
    row of zeros): a transposed matrix would put texture 1's confusions in the column of 1."""
    from bench.reporting.experiment_report import confusion_rows

    train, valid = separated_case(T=5)
    model = ex.fit_model(train)
    one, two = (ex.simulate(model, valid, t, n_sims=4, seed=0) for t in (1, 2))
    decided = np.array([2, 2, 1, 3])
    one = dataclasses.replace(one, decided=decided, correct=decided == 1)
    assert two.decided.tolist() == [2, 2, 2, 2]
    assert confusion_rows([one, two]) == [{"true": 1, "1": 1, "2": 2, "3": 1},
                                          {"true": 2, "1": 0, "2": 4, "3": 0},
                                          {"true": 3, "1": 0, "2": 0, "3": 0}]


def test_the_probability_evolution_plots_the_prior_and_every_posterior_of_a_simulation():
    """probability_evolution.png (experiment_report.posterior_lines, like D Fig. 6-10): for the first simulation,
    points at 0 … n movements — the equal prior, then the posterior after each movement, the last one the decision's
    (above the threshold for the true texture) — for the five likeliest textures."""
    from bench.reporting.experiment_report import posterior_lines

    train, valid = separated_case(T=8)
    model = ex.fit_model(train)
    r = ex.simulate(model, valid, 3, n_sims=2, seed=0)
    n = int(r.n_moves[0])
    lines = posterior_lines(r)
    assert n >= 1 and len(lines) == 5
    for label, moves, probability in lines:
        assert moves.tolist() == list(range(n + 1)) and probability[0] == pytest.approx(1 / 8)
    final = {label: probability[-1] for label, _, probability in lines}
    assert final["T3"] > r.threshold and r.decided[0] == 3

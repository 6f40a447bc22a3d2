"""Texture identification by Bayesian exploration (D ch. 6, Tables 6-4 and 6-5): the shipped experiment
(``fixtures/experiments/fishel2012.toml``) end to end on the emulated sensor, with two ablations (a skin without
fingerprints; wear without replacement).  Stage results are cached in ``out/cache`` by content hash, so a second
run of the claims re-runs no sliding.  The accuracy is emergent from the physics, the library and the noise;
nothing was tuned toward it, and the rows the model does not reproduce say so."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy import stats

from bench.experiments import exploration as ex
from bench.experiments.experiment import (ablated, beats_baselines, load_experiment, movement_label, run_experiment,
                                          summary, table_from_rows)
from bench.experiments.pairs import nearest_neighbour_sigma, pair_separation_sigma
from bench.paths import FIXTURES, OUT
from bench.verification.claims.core import Bench, Claim, claim_group
from emulator.skin import Skin

EXPERIMENT = FIXTURES / "experiments" / "fishel2012.toml"


#: |Spearman ρ| a trend over the 36 movements must reach: two-sided p < 0.05 for 36 points (ρ_crit ≈ 0.33)
TREND_RHO = 0.33


def pilot_trends(pilot_rows: list[dict]) -> dict:
    """What D's pilot-trend sentence is checked with, from the pilot's trials (traction in A, roughness in ln
    units):

    * per property, Spearman ρ of the pilot's expected uncertainty U (equal priors over the pilot textures) against
      the movement's force and velocity, over every movement the pilot ran — the high-power ones included, as in
      D Fig. 6-7 — and over the kept (not high-power) ones: ``{"traction": {"force": ρ, "velocity": ρ,
      "force_kept": ρ, "velocity_kept": ρ}, …}``; ρ < 0: the property discriminates better (U falls) as force or
      velocity rises;
    * per velocity (cm/s) and per force (N), medians over the textures and the other axis of what U weighs: the
      trial scatter (traction's SD relative to its mean, %; roughness's SD), the spread of the textures' means
      (roughness's SD across textures), each texture's separation from its nearest neighbour in units of their
      pooled trial SD (d′, per property), and the textures' median roughness;
    * per force, the velocity (cm/s) of the highest roughness U."""
    model = ex.fit_model(table_from_rows(pilot_rows))
    u = ex.pilot_uncertainty(model)
    grid = ex.movement_grid()
    force, velocity = grid["force_N"][model.movements], grid["velocity_m_s"][model.movements]
    kept = ~grid["high_power"][model.movements]

    def rho(x, y):
        return float(stats.spearmanr(x, y)[0])

    out = {name: {"force": rho(u[:, p], force), "velocity": rho(u[:, p], velocity),
                  "force_kept": rho(u[kept, p], force[kept]), "velocity_kept": rho(u[kept, p], velocity[kept])}
           for p, name in enumerate(ex.PROPERTIES)}
    mean, sigma = model.mean, model.sigma  # (T, M, 3)
    # d′ of each texture to its nearest neighbour, per movement and property: |Δµ| / √((σ_i² + σ_j²)/2)
    gap = np.abs(mean[:, None] - mean[None, :]) / np.sqrt(0.5 * (sigma[:, None] ** 2 + sigma[None, :] ** 2))
    gap[np.arange(mean.shape[0]), np.arange(mean.shape[0])] = np.inf
    nearest = gap.min(axis=1)  # (T, M, 3)

    def medians(sel) -> dict:
        return {"traction_rel_sd_pct": float(np.median(100 * sigma[:, sel, 0] / np.abs(mean[:, sel, 0]))),
                "traction_nearest_dprime": float(np.median(nearest[:, sel, 0])),
                "roughness_trial_sd": float(np.median(sigma[:, sel, 1])),
                "roughness_texture_sd": float(np.median(np.std(mean[:, sel, 1], axis=0))),
                "roughness_nearest_dprime": float(np.median(nearest[:, sel, 1])),
                "roughness_median": float(np.median(mean[:, sel, 1]))}

    out["per_velocity_cm_s"] = {f"{100 * v:.3g}": medians(velocity == v) for v in np.unique(velocity)}
    out["per_force_N"] = {f"{f:.3g}": medians(force == f) for f in np.unique(force)}
    out["roughness_worst_velocity_cm_s_per_force_N"] = {
        f"{f:.3g}": float(100 * velocity[force == f][np.argmax(u[force == f, 1])]) for f in np.unique(force)}
    return out


def _run(spec, b: Bench):
    """The experiment ``spec`` on ``b``'s cluster (``claims --scheduler/--workers``; default from the environment)."""
    from bench.campaigns.engine import ClusterSpec

    return run_experiment(spec, cache_dir=OUT / "cache", cluster=b.cluster or ClusterSpec.from_env(),
                          progress=False, log=lambda m: None)


@claim_group("exploration")
def exploration_claims(b: Bench) -> list[Claim]:
    spec = replace(load_experiment(EXPERIMENT), fidelity=b.fidelity)
    base = _run(spec, b)
    s = summary(base)
    pairs, ident = s["pairs/bayesian"], s["identification/bayesian"]
    n_val = len({t for p in base.pairs for t in p})
    beats, strictly = beats_baselines(base), beats_baselines(base, strict=True)
    model = ex.fit_model(table_from_rows(base.training_rows))
    nearest = nearest_neighbour_sigma(model, sorted({t for p in base.pairs for t in p}))
    pair_gap = min(max(sep) for sep in pair_separation_sigma(model, base.pairs))
    gaps = sorted(sep for sep, _ in nearest.values())
    picks = ", ".join(f"{p} {movement_label(m)}" for p, m in zip(ex.PROPERTIES, base.best_movements))
    too_easy = (f"the pilot's picks ({picks}) separate the validation textures from every other texture by "
                f"≥ {gaps[0]:.1f} training σ (median {float(np.median(gaps)):.1f}) in the most separating property "
                f"and movement, so two or three movements settle the posterior; D's trials scattered more against "
                f"the textures' differences than the model's, whose trial-to-trial spread is the sensor noise, the "
                f"force control and where on the square a trial starts (bench/tests/test_trial_spread.py) — other "
                f"sources of a real rig's variation are not modelled and none was added to move this figure")
    smooth = summary(_run(ablated(spec, "smooth-skin")[0], b))["identification/bayesian"]["accuracy"]
    worn = summary(_run(ablated(spec, "unreplaced-wear")[0], b))["identification/bayesian"]["accuracy"]
    # measured (docs/experiment/README.md): the validation pairs are D's kind of pairs, similar in description
    # (bench/experiments/pairs.py, chosen before any accuracy was seen); validation trials scatter like training
    # trials since the skin is replaced at the first visible wear; every trial of a texture runs on its one 75 mm
    # square (bench/rigs/texture_rig.py), so trials of one texture overlap and scatter less than on fresh stretches
    return [
        Claim("pairs of similar textures: Bayesian exploration accuracy", "≥ 99 % (D: 99.6 %)",
              100 * pairs["accuracy"], 99.0, 100.0, "%", "D ch. 6 Table 6-4", {"pairs": base.pairs},
              kind="prediction"),
        Claim("pairs: median movements to converge", "2–5 (D: 3)", pairs["median_moves"], 2.0, 5.0, "movements",
              "D ch. 6 Table 6-4", kind="prediction",
              deviation=f"{pairs['median_moves']:g} movement(s): each pair lies ≥ {pair_gap:.1f} training σ apart "
                        f"in its most separating property (report.md), so the first movement usually takes the "
                        f"posterior past 99.9 %. D needed 3: D's trials scattered more against the pairs' differences "
                        f"than the model's, whose spread is the sensor noise, the force control and where on the "
                        f"square a trial starts (bench/tests/test_trial_spread.py); other sources of trial-to-trial "
                        f"variation of a real rig are not modelled"),
        Claim("117-way identification of the validation textures: accuracy", "90–99 % (D: 95.4 %)",
              100 * ident["accuracy"], 90.0, 99.0, "%", "D ch. 6 Table 6-5",
              {"nearest_texture_sigma": {str(t): v for t, v in nearest.items()}}, kind="prediction"),
        Claim("117-way identification: median movements", "3–7 (D: 5)",
              ident["median_moves"] if math.isfinite(ident["median_moves"]) else 99.0, 3.0, 7.0, "movements",
              "D ch. 6 Table 6-5", kind="prediction", deviation=f"fewer than D's: {too_easy}"),
        Claim("Bayesian exploration beats cycling and random choice", f"on ≥ 14 of {n_val} textures", float(beats),
              14.0, float(n_val), "textures", "D ch. 6", {"per_strategy": {k: v["accuracy"] for k, v in s.items()},
                                                      "strictly_better_on": strictly},
              kind="prediction",
              note=f"at least as accurate as both, and no more movements (medians), per texture; strictly better "
                   f"than both (better in one of the two, no worse in the other) on {strictly} of {n_val}: the "
                   f"others tie, most at 100 % in the same median number of movements"),
        *_pilot_trend_claims(pilot_trends(base.pilot_rows)),
        Claim("removing the fingerprints lowers 117-way accuracy", "lower than with ridges",
              100 * (ident["accuracy"] - smooth), 0.0, math.inf, "points", "D ch. 4, 6",
              {"with_ridges": ident["accuracy"], "smooth": smooth}, kind="prediction"),
        Claim("skin wear without replacement lowers 117-way accuracy", "lower than with replacement",
              100 * (ident["accuracy"] - worn), 0.0, math.inf, "points", "D ch. 6",
              {"replaced": ident["accuracy"], "never_replaced": worn}, kind="prediction"),
    ]


def _pilot_trend_claims(rho: dict) -> list[Claim]:
    """D ch. 6: "the ability to discriminate traction improved at lower velocities and higher forces, while the
    ability to discriminate roughness improved at higher velocities and lower forces" — as the sign of Spearman ρ
    between the pilot's U and the movement's force or velocity over the 36 movements, |ρ| ≥ 0.33."""
    src, note = "D ch. 6 (pilot, Fig. 6-7 text)", ("Spearman ρ of the pilot's U (10 textures, equal priors) "
                                                  "against the movement over all 36 movements; |ρ| ≥ 0.33 is "
                                                  "p < 0.05 for 36 points")
    tr, ro = rho["traction"], rho["roughness"]
    per_v, per_f = rho["per_velocity_cm_s"], rho["per_force_N"]
    v_lo, v_hi = per_v[min(per_v, key=float)], per_v[max(per_v, key=float)]
    f_lo, f_hi = per_f[min(per_f, key=float)], per_f[max(per_f, key=float)]
    worst = rho["roughness_worst_velocity_cm_s_per_force_N"]
    worst_v = max(set(worst.values()), key=list(worst.values()).count)
    rough_peak_f = max(per_f, key=lambda f: per_f[f]["roughness_median"])

    def span(key, rows, fmt=".2f"):
        return " → ".join(f"{rows[k][key]:{fmt}}" for k in sorted(rows, key=float))

    def trend(name: str, measured: float, axis: str, u_rises: bool, details=None, deviation: str = "") -> Claim:
        """D's "discriminates better at lower/higher <axis>" as U rising/falling with it: |ρ| ≥ TREND_RHO."""
        expected = (f"U rises with {axis}: ρ ≥ {TREND_RHO}" if u_rises else f"U falls with {axis}: ρ ≤ −{TREND_RHO}")
        low, high = (TREND_RHO, 1.0) if u_rises else (-1.0, -TREND_RHO)
        return Claim(f"pilot: {name}", expected, measured, low, high, "Spearman ρ", src, details or {},
                     kind="prediction", note=note, deviation=deviation)

    return [
        trend("traction discriminates better at higher force", tr["force"], "force", False, details=rho),
        trend("traction discriminates better at lower velocity", tr["velocity"], "velocity", True,
              deviation=f"ρ = {tr['velocity']:.2f} over the 36 movements ({tr['velocity_kept']:+.2f} over the 21 "
                        f"kept ones, D's sign but not significant there). The model's traction does scatter more "
                        f"when faster, in D's direction (trial SD {span('traction_rel_sd_pct', per_v)} % of the "
                        f"mean from 1 to 10 cm/s), but the textures' means draw apart faster than that (each "
                        f"one's nearest neighbour at a median d′ of {span('traction_nearest_dprime', per_v)}), so "
                        f"U does not rise; D saw \"more stable sliding forces as measured by the motor current\" "
                        f"at slower velocities"),
        trend("roughness discriminates better at higher velocity", ro["velocity"], "velocity", False,
              deviation=f"ρ = {ro['velocity']:.2f} ({ro['velocity_kept']:+.2f} over the kept movements): from 1 "
                        f"to 10 cm/s the textures' mean roughness spreads wider (SD across textures "
                        f"{v_lo['roughness_texture_sd']:.2f} → {v_hi['roughness_texture_sd']:.2f}) but their "
                        f"trials scatter more too (SD {v_lo['roughness_trial_sd']:.3f} → "
                        f"{v_hi['roughness_trial_sd']:.3f}); the nearest-neighbour d′ is "
                        f"{span('roughness_nearest_dprime', per_v)}, and roughness is least informative at "
                        f"{worst_v:.3g} cm/s for {list(worst.values()).count(worst_v)} of the {len(worst)} forces, "
                        f"where the ridges' second harmonic 2v/pitch is "
                        f"{2e-2 * worst_v / Skin().ridge_pitch_m:.0f} Hz, beside the ~330 Hz resonance — no "
                        f"monotone trend"),
        trend("roughness discriminates better at lower force", ro["force"], "force", True,
              deviation=f"ρ = {ro['force']:.2f} ({ro['force_kept']:+.2f} over the kept movements), the opposite "
                        f"sign: in the model the textures' median roughness rises with force up to "
                        f"{rough_peak_f} N (medians {span('roughness_median', per_f)} ln units from "
                        f"{min(per_f, key=float)} to {max(per_f, key=float)} N; docs/experiment/force_damping.md) "
                        f"while each texture's trials scatter less (SD {f_lo['roughness_trial_sd']:.3f} → "
                        f"{f_hi['roughness_trial_sd']:.3f}) and the textures' spread stays "
                        f"{f_lo['roughness_texture_sd']:.2f} → {f_hi['roughness_texture_sd']:.2f}: roughness "
                        f"separates better with force, not worse"),
    ]

"""Texture identification by Bayesian exploration (D ch. 6, Tables 6-4 and 6-5): the shipped experiment
(``fixtures/experiments/fishel2012.toml``) end to end on the emulated sensor, with two ablations (a skin without
fingerprints; wear without replacement).  Stage results are cached in ``out/cache`` by content hash, so a second
run of the claims re-runs no sliding.  The accuracy is emergent from the physics, the library and the noise;
nothing was tuned toward it, and the rows the model does not reproduce say so."""

from __future__ import annotations

import math
from dataclasses import replace

from bench.experiments.experiment import ABLATIONS, beats_baselines, load_experiment, run_experiment, summary
from bench.paths import FIXTURES, OUT
from bench.verification.claims.core import Bench, Claim, claim_group

EXPERIMENT = FIXTURES / "experiments" / "fishel2012.toml"


def _run(spec):
    from bench.campaigns.engine import ClusterSpec

    return run_experiment(spec, cache_dir=OUT / "cache", cluster=ClusterSpec.from_env(), progress=False,
                          log=lambda m: None)


@claim_group("exploration")
def exploration_claims(b: Bench) -> list[Claim]:
    spec = replace(load_experiment(EXPERIMENT), fidelity=b.fidelity)
    base = _run(spec)
    s = summary(base)
    pairs, ident = s["pairs/bayesian"], s["identification/bayesian"]
    n_val = len({t for p in base.pairs for t in p})
    beats = beats_baselines(base)
    smooth = summary(_run(replace(spec, **ABLATIONS["smooth-skin"][1])))["identification/bayesian"]["accuracy"]
    worn = summary(_run(replace(spec, **ABLATIONS["unreplaced-wear"][1])))["identification/bayesian"]["accuracy"]
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
              deviation="1 movement: with every trial on its texture's one 75 mm square, as D's were, each pair "
                        "lies ≥ 4.1 training σ apart in its most separating property (report.md), so the first "
                        "movement usually takes the posterior past 99.9 %. D needed 3: D's trials scattered more "
                        "against the pairs' differences than the model's, whose spread is the sensor noise, the force "
                        "control and where on the square a trial starts (bench/tests/test_trial_spread.py); other "
                        "sources of trial-to-trial variation of a real rig are not modelled"),
        Claim("117-way identification of the validation textures: accuracy", "90–99 % (D: 95.4 %)",
              100 * ident["accuracy"], 90.0, 99.0, "%", "D ch. 6 Table 6-5", kind="prediction"),
        Claim("117-way identification: median movements", "3–7 (D: 5)",
              ident["median_moves"] if math.isfinite(ident["median_moves"]) else 99.0, 3.0, 7.0, "movements",
              "D ch. 6 Table 6-5", kind="prediction"),
        Claim("Bayesian exploration beats cycling and random choice", f"on ≥ 14 of {n_val} textures", float(beats),
              14.0, float(n_val), "textures", "D ch. 6", {"per_strategy": {k: v["accuracy"] for k, v in s.items()}},
              kind="prediction", note="at least as accurate as both, and no more movements (medians), per texture",
              deviation="on 13 of 16: overall Bayesian exploration leads (97.3 % against cycling 96.7 % and random "
                        "94.7 %), but cycling the three best movements is more accurate on cotton percale (82 % "
                        "against 100 %), newsprint (96 % against 100 %) and polyester taffeta (99.8 % against 100 %): "
                        "percale lies 0.3 σ from poplin in traction and 1.1 σ in fineness, and on textures with a "
                        "neighbour within ~1 σ in two properties the single most informative-looking property "
                        "misleads, where forced variety helps"),
        Claim("removing the fingerprints lowers 117-way accuracy", "lower than with ridges",
              100 * (ident["accuracy"] - smooth), 0.0, math.inf, "points", "D ch. 4, 6",
              {"with_ridges": ident["accuracy"], "smooth": smooth}, kind="prediction"),
        Claim("skin wear without replacement lowers 117-way accuracy", "lower than with replacement",
              100 * (ident["accuracy"] - worn), 0.0, math.inf, "points", "D ch. 6",
              {"replaced": ident["accuracy"], "never_replaced": worn}, kind="prediction"),
    ]

"""Throughput of virtual Bayesian exploration: exploration steps per second on D's full scale — 117 synthetic
textures × 36 movements × 3 properties (target ≥ 10 000 steps/s).

Run ``python -m bench.experiments.bench_exploration [--sims N] [--textures N] [--seed S] [--backend B]``. A step is one
exploratory movement of one simulation (choice, draw, posterior update); the rate counts the steps the
simulations made over the wall time of :func:`~bench.experiments.exploration.simulate` (the one-off confusion
matrices, built once per candidate set, and the compiled kernel's first load are timed separately).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from bench.experiments import exploration as ex


def synthetic_tables(n_textures: int = 117, n_movements: int = 36, n_train: int = 5, n_valid: int = 5,
                     seed: int = 0) -> tuple[ex.TrialTable, ex.TrialTable]:
    """(training, validation) trial tables of synthetic textures: each texture has a latent value per property
    (uniform in [0, 1]); at movement m its property p reads ``gain[m, p]·latent + 0.2·idiosyncratic[t, m, p]``
    with trial noise σ[t, m, p] = ``noise[m, p]`` × log-normal spread, ``noise`` ranging from 0.005 to 0.1 across
    movements (some movements are much more informative than others, as in D Fig. 6-7)."""
    rng = np.random.default_rng(seed)
    P = len(ex.PROPERTIES)
    latent = rng.random((n_textures, 1, P))
    gain = rng.uniform(0.5, 1.5, (1, n_movements, P))
    mu = gain * latent + 0.2 * rng.standard_normal((n_textures, n_movements, P))
    sigma = 10.0 ** rng.uniform(-1.6, -0.6, (1, n_movements, P)) * rng.lognormal(0.0, 0.3, mu.shape)
    n = n_train + n_valid
    t, m, p, k = np.meshgrid(np.arange(n_textures), np.arange(n_movements), np.arange(P), np.arange(n),
                             indexing="ij")
    values = mu[..., None] + sigma[..., None] * rng.standard_normal(t.shape)
    train = k < n_train
    tables = []
    for sel, offset in ((train, 0), (~train, n_train)):
        tables.append(ex.TrialTable(t[sel] + 1, m[sel], p[sel], k[sel] - offset, values[sel]))
    return tables[0], tables[1]


def main(argv=None) -> float:
    """Print the throughput per strategy and return the Bayesian strategy's steps per second."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sims", type=int, default=200, help="simulations per true texture (default 200)")
    ap.add_argument("--textures", type=int, default=16, help="true textures simulated (default 16, as D)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--backend", choices=("auto", "numba", "numpy"), default="auto",
                    help="how the expected uncertainty is computed (default auto: numba when available)")
    args = ap.parse_args(argv)

    train, valid = synthetic_tables(seed=args.seed)
    model = ex.fit_model(train)
    t0 = time.perf_counter()
    ctx = ex.prepare(model, backend=args.backend)
    prep = time.perf_counter() - t0
    t0 = time.perf_counter()
    k = ctx.mean.shape[0]
    ex.uncertainty_rows(ctx.confusion, np.full((1, k), 1.0 / k), backend=args.backend)  # JIT compile or load
    warm = time.perf_counter() - t0
    T, M, P = model.mean.shape
    print(f"{T} textures × {M} movements × {P} properties; confusion matrices and pilot: {prep * 1e3:.0f} ms; "
          f"kernel compile/load: {warm * 1e3:.0f} ms (not counted)")
    rng = np.random.default_rng(args.seed)
    truths = rng.choice(model.textures, size=min(args.textures, T), replace=False)
    rate = float("nan")
    for name in ("bayesian", "cycle", "random"):
        results, t0 = [], time.perf_counter()
        for tex in truths:
            results.append(ex.simulate(model, valid, int(tex), strategy=name, n_sims=args.sims, seed=args.seed,
                                       context=ctx))
        wall = time.perf_counter() - t0
        steps = int(sum(r.n_moves.sum() for r in results))
        print(f"{name:>8}: {steps} steps in {wall:.2f} s = {steps / wall:,.0f} steps/s; accuracy "
              f"{ex.accuracy(results):.1%}, median movements {ex.median_moves(results):g}")
        if name == "bayesian":
            rate = steps / wall
    print(f"bayesian exploration: {rate:,.0f} steps/s (target >= 10,000)")
    return rate


if __name__ == "__main__":
    main()

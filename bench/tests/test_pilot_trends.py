"""The pilot-trend claims' measure (bench/verification/claims/exploration.py): Spearman ρ of the pilot's expected
uncertainty U against the movement's force and velocity.  On synthetic pilots whose textures separate better at
one end of the grid, ρ must have the sign the claims read as "discriminates better" — a sign slip would turn a
deviation into a pass (or the reverse) without anyone noticing."""

import numpy as np
import pytest

from bench.experiments import exploration as ex
from bench.verification.claims.exploration import TREND_RHO, pilot_trends

pytestmark = pytest.mark.unit

GRID = ex.movement_grid()


def _pilot(spread_of, trials: int = 4, textures: int = 5, seed: int = 0) -> list[dict]:
    """Trial rows of a synthetic pilot: texture i's mean of each property is i × spread_of(property, force,
    velocity), every trial scattered by a unit normal — so the textures separate more where the spread is larger."""
    rng = np.random.default_rng(seed)
    rows = []
    for tex in range(textures):
        for m in GRID["movement"]:
            f, v = GRID["force_N"][m], GRID["velocity_m_s"][m]
            for k in range(trials):
                vals = {p: tex * spread_of(p, f, v) + rng.standard_normal() for p in ex.PROPERTIES}
                rows.append({"texture": tex, "movement_id": int(m), "trial": k, **vals})
    return rows


def test_textures_separating_with_force_give_negative_rho_against_force():
    rho = pilot_trends(_pilot(lambda p, f, v: 3.0 * f if p == "traction" else 1.0))
    assert rho["traction"]["force"] <= -TREND_RHO  # the claim "traction discriminates better at higher force" passes
    assert abs(rho["traction"]["velocity"]) < TREND_RHO  # and no velocity trend is invented


def test_textures_separating_with_velocity_give_negative_rho_against_velocity():
    rho = pilot_trends(_pilot(lambda p, f, v: 60.0 * v if p == "roughness" else 1.0))
    assert rho["roughness"]["velocity"] <= -TREND_RHO
    assert abs(rho["roughness"]["force"]) < TREND_RHO


def test_textures_separating_at_low_force_give_positive_rho_against_force():
    rho = pilot_trends(_pilot(lambda p, f, v: 1.0 / f if p == "roughness" else 1.0))
    assert rho["roughness"]["force"] >= TREND_RHO  # "roughness discriminates better at lower force" passes


def test_the_scatter_per_velocity_reads_the_trials_spread():
    rho = pilot_trends(_pilot(lambda p, f, v: 2.0, trials=30))
    per_v = rho["per_velocity_cm_s"]
    assert len(per_v) == 6
    for row in per_v.values():
        assert row["roughness_trial_sd"] == pytest.approx(1.0, rel=0.2)  # the unit normal's SD
        assert row["roughness_texture_sd"] == pytest.approx(2.0 * np.std(np.arange(5)), rel=0.1)

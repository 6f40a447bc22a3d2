"""A trial's ridge gain (emulator.skin.Skin.trial_gain): the ridge factor, scattered from trial to trial by a relative
spread of ``irregularity × worn fraction`` (the skin module's docstring), never below zero."""

import numpy as np
import pytest

from emulator.skin import Skin


@pytest.mark.unit
def test_a_trials_ridge_gain_scatters_more_as_the_ridges_wear_and_is_never_negative():
    """New ridges give every trial the gain 1 exactly; ridges worn to half their 0.2 mm give gains of mean 0.5 and
    relative spread irregularity × 0.5 (within 10 % over 4000 trials); ridges worn to a tenth, whose spread
    reaches below zero, give gains ≥ 0 (a negative gain would turn the ridges' vibration over), some exactly 0."""
    rng = np.random.default_rng(3)
    new = Skin()
    assert {new.trial_gain(rng) for _ in range(100)} == {1.0}
    half = Skin(ridge_height_m=0.1e-3)
    gains = np.array([half.trial_gain(rng) for _ in range(4000)])
    assert gains.mean() == pytest.approx(0.5, abs=0.01)
    assert gains.std() / gains.mean() == pytest.approx(half.irregularity * 0.5, rel=0.1)
    worn = Skin(ridge_height_m=0.02e-3, irregularity=2.0)
    gains = np.array([worn.trial_gain(rng) for _ in range(4000)])
    assert gains.min() == 0.0 and np.count_nonzero(gains == 0.0) > 100
    assert Skin(fingerprints=False).trial_gain(rng) == 0.0

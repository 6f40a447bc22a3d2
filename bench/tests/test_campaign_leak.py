"""The fault campaign's mechanical fault: a punctured skin leaks its fluid while the bridge firmware streams, and the
resting PDC the host driver hands over falls as the pressure–volume curve predicts — in every campaign scene (taps,
sphere drops and a press on top of the leak).  The check is not vacuous: a healthy finger, or one leaking at half
the rate, fails it."""

import pytest

from bench.campaigns import faults as campaign
from bench.campaigns.faults import FaultCase, run_case


@pytest.mark.unit
@pytest.mark.parametrize("scene", list(campaign.SCENES))
def test_a_leaking_finger_shows_its_falling_pressure_through_firmware_and_driver(scene):
    result = run_case(campaign.FAULTS["fluid_leak"], scene, 1)
    assert result["passed"], result["problem"]


@pytest.mark.unit
@pytest.mark.parametrize("rate, words", [(None, "fell by 0.0 codes"), (campaign.LEAK_CASE_ML_PER_MIN / 2, "fell by 2")])
def test_the_leak_check_fails_for_a_healthy_finger_and_for_a_slower_leak(rate, words):
    faults = {} if rate is None else {"sensor_faults": {"fluid_leak_mL_per_min": rate}}
    case = FaultCase("fluid_leak", "test", faults, [], campaign.FAULTS["fluid_leak"].check)
    result = run_case(case, "rest", 1)
    assert not result["passed"]
    assert words in result["problem"] and "the leak predicts 4" in result["problem"]

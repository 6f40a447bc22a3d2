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
@pytest.mark.parametrize("rate, words", [(None, "fell by 0.0 codes"), (campaign.LEAK_CASE_ML_PER_MIN / 2, "fell by 2"),
                                         (campaign.LEAK_CASE_ML_PER_MIN * 0.75, "fell by 3"),
                                         (campaign.LEAK_CASE_ML_PER_MIN * 1.25, "fell by 5")])
def test_the_leak_check_fails_for_a_healthy_finger_and_for_a_leak_a_quarter_off(rate, words):
    """The check's band is the predicted drop (~43 codes here) ± 15 % + 2 codes: a leak 25 % slower or faster (drops
    of ~34 and ~53 codes) falls outside it, on either side."""
    faults = {} if rate is None else {"sensor_faults": {"fluid_leak_mL_per_min": rate}}
    case = FaultCase("fluid_leak", "test", faults, [], campaign.FAULTS["fluid_leak"].check)
    result = run_case(case, "rest", 1)
    assert not result["passed"]
    assert words in result["problem"] and "the leak predicts 4" in result["problem"]


@pytest.mark.unit
def test_the_leak_check_refuses_a_run_without_enough_clean_pdc():
    """Every sample flagged from 0.3 s on (bad parity): ~30 frames have a clean PDC, enough for the two medians of
    LEAK_CASE_FRAMES but too close together to measure the leak by, so the check fails saying how few there were
    (it needs 4 × LEAK_CASE_FRAMES)."""
    from emulator.spi.model import Faults

    kw, _, check = campaign.FAULT_CASES["fluid_leak"]
    flagged = FaultCase("fluid_leak under bad parity", "test", kw,
                        [(0.3, lambda b: setattr(b.bus.ports[1], "faults", Faults(bad_parity=True)))], check)
    result = run_case(flagged, "rest", 1)
    assert not result["passed"] and result["problem"].endswith("frames with a clean PDC"), result
    assert int(result["problem"].split()[1]) < 4 * campaign.LEAK_CASE_FRAMES

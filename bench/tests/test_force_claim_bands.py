"""The force group's knee and creep rows derive their accepted ranges from the sensor's parameters (a read-back
within D's bounds); a sensor whose read-back band lies wholly outside those bounds would invert a range (low above
high: no reading could pass, and the table would print it).  Such a sensor is refused before any claim runs, one
line naming the parameter, its value and why; every other sensor in the parameters' ranges gets ranges in order."""

import itertools

import pytest

from bench.verification.claims import Bench, run_claims, run_claims_over_seeds
from bench.verification.claims import force
from emulator.params import PARAMETER_FIELDS, SensorParams

pytestmark = pytest.mark.unit


def _span(name: str, n: int) -> list[float]:
    lo, hi = PARAMETER_FIELDS[name].metadata["range"]
    return [lo + (hi - lo) * k / (n - 1) for k in range(n)]


def test_a_sensor_is_refused_exactly_when_a_band_would_invert():
    """Over the parameters' whole ranges (the knee's slope, the skin's relaxed fraction and relaxation time): the
    force group refuses a sensor if and only if one of the two ranges it would use has its low end above its high
    end, and each refusal names the parameter whose band inverts."""
    refused = seen = 0
    for knee, r, tau in itertools.product(_span("force_slope_above_knee", 11),
                                          _span("skin_relaxed_modulus_fraction", 8),
                                          [1e-3, 0.1, 1.0, 10.0, 100.0]):
        p = SensorParams().replace(force_slope_above_knee=knee, skin_relaxed_modulus_fraction=r,
                                   skin_relaxation_time_s=tau)
        knee_band, creep_band = force.knee_band(p), force.creep_band_percent(p)
        problems = force.unclaimable(p)
        assert [b[0] > b[1] for b in (knee_band, creep_band)] == [
            any(q.startswith(f"sensor.{name} = ") for q in problems)
            for name in ("force_slope_above_knee", "skin_relaxed_modulus_fraction")], (knee, r, tau, problems)
        refused += bool(problems)
        seen += 1
    assert 0 < refused < seen  # (both kinds of sensor met)
    assert force.unclaimable(SensorParams()) == []


@pytest.mark.parametrize("change, expected", [
    ({"force_slope_above_knee": 0.6},
     "the force claims cannot judge this sensor: sensor.force_slope_above_knee = 0.6: the knee row accepts its "
     "read-back ± 10 % and below D's clear departure (< 0.5), so above 0.5556 no reading can pass (leave the group "
     "out, --only, or change the sensor)"),
    ({"skin_relaxed_modulus_fraction": 1.0},
     "the force claims cannot judge this sensor: sensor.skin_relaxed_modulus_fraction = 1 with "
     "sensor.skin_relaxation_time_s = 1 s: the skin's creep law gives 0 % from 0.2 to 10 s; the creep row accepts "
     "its read-back ± 1 point and within 2–15 % (creep present and bounded), so outside a law of 1–16 % no reading "
     "can pass (leave the group out, --only, or change the sensor)"),
])
def test_claims_on_a_sensor_that_would_invert_a_band_are_refused_in_one_line(change, expected):
    """Refused before anything runs, one seed or several (no cluster is started); the groups that can judge the
    sensor still run on it."""
    bench = Bench(params=SensorParams().replace(**change))
    with pytest.raises(ValueError) as e:
        run_claims(bench, ["scales", "force"])
    assert str(e.value) == expected
    with pytest.raises(ValueError, match="the force claims cannot judge this sensor"):
        run_claims_over_seeds(lambda seed: Bench(seed=seed, params=bench.params), [1, 2], ["force"])
    assert run_claims(bench, ["scales"])

"""The bridge turns fluid pressure (Pa) into volts without touching its input: a recorded ``fluid_pressure_Pa`` stays
in pascals on every profile, whether or not the duct resonance filters it first (a bridge scaling its input in place
once turned the recorded pressure of the fast and default profiles into bridge volts)."""

import numpy as np
import pytest

from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.stimuli import Press

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("fidelity", ["fast", "default", "reference"])
def test_the_recorded_fluid_pressure_stays_in_pascals_through_the_bridge(fidelity):
    p = SensorParams()
    sensor = Sensor(p, [Press(0.2, 1.0, 0.1, 0.5)], ("PDC",), fidelity, 1, NoiseSources.none(),
                    record_signals=("fluid_pressure_Pa",))
    t = np.array([0.0, 0.1, 0.45, 0.6])  # s: at rest, at rest, pressed at 1 N, held
    pa = sensor.signal("fluid_pressure_Pa", t)
    assert pa[:2] == pytest.approx([p.resting_pressure_Pa] * 2, rel=1e-6)
    assert np.all(pa[2:] > p.resting_pressure_Pa + 1e3)  # a 1 N press raises the fluid pressure by kPa

"""The bridge turns fluid pressure (Pa) into volts without touching its input: a recorded ``fluid_pressure_Pa`` stays
in pascals on every profile, whether or not the duct resonance filters it first (a bridge scaling its input in place
once turned the recorded pressure of the fast and default profiles into bridge volts); and the core temperature that
drives its drift moves sample by sample, not block by block."""

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


def test_the_core_temperature_moves_within_a_block_as_across_blocks():
    """CoreTemperature gives each grid instant its own core temperature (°C): warming from power-on, a 2 s block rises
    through it, and its last sample is what a one-sample block at that instant reads — the bridge's drift does not
    step at block boundaries."""
    from emulator import thermal
    from emulator.effects import Block
    from emulator.transducer import CoreTemperature

    def core():
        events = thermal.ThermalEvents([], power_on_s=0.0)  # warming from ambient: the temperature moves every step
        return CoreTemperature(thermal.ThermalModel(SensorParams(), events, seed=0, noise=False))

    fs, n = 4400.0, 8800
    long = core().process(Block(0, n, fs), {})["bridge_temperature_C"]
    last = core().process(Block(n - 1, 1, fs), {})["bridge_temperature_C"]
    assert long.shape == (n,) and long[-1] > long[0] + 1e-3  # K: it warms within the block
    assert long[-1] == pytest.approx(last[0], abs=1e-9)

"""The settled-at-rest thermal shortcut (:func:`emulator.thermal.steady_state`): the core temperature (°C), TDC and
TAC (V) a sensor with nothing thermal happening reads, without the thermal network running."""

import numpy as np
import pytest

from emulator import thermal
from emulator.params import SensorParams
from emulator.units import unit

pytestmark = pytest.mark.unit

#: parameters whose shortcut is compared: nominal, a unit of the population, a warm room, and rails so low that
#: TDC (~5 V) and TAC's 1.65 V bias are clipped
PARAMS = {"nominal": SensorParams(), "unit 3": unit(3).params,
          "40 °C room": SensorParams().replace(ambient_temperature_C=40.0),
          "1 V rail": SensorParams().replace(supply_rail_V=1.0)}


@pytest.mark.parametrize("name", PARAMS)
@pytest.mark.parametrize("thermistor", [None, "open", "short"])
@pytest.mark.parametrize("heater_failed", [False, True])
def test_the_shortcut_equals_the_settled_network_to_the_bit(name, thermistor, heater_failed):
    """What the shortcut serves equals, bit for bit, what a thermal network built with no events serves at t = 0
    (core °C, TDC V, TAC V), for every thermistor fault, a failed heater and rails that clip."""
    p = PARAMS[name]
    faults = {k: v for k, v in (("thermistor", thermistor), ("heater_failed", heater_failed)) if v}
    model = thermal.ThermalModel(p, thermal.ThermalEvents([]), seed=0, faults=faults)
    served = tuple(float(model.value_at(np.zeros(1), column)[0]) for column in range(3))
    assert thermal.steady_state(p, faults) == served


def test_the_shortcut_builds_no_thermal_network_model(monkeypatch):
    """The shortcut is the cheap path: it solves the settled state and builds no :class:`ThermalModel` (whose
    filters, history and noise generator it never uses)."""
    def refuse(*args, **kwargs):
        raise AssertionError("steady_state built a ThermalModel")

    monkeypatch.setattr(thermal, "ThermalModel", refuse)
    thermal._steady_state.cache_clear()
    p = SensorParams().replace(ambient_temperature_C=21.5)
    core, tdc, tac = thermal.steady_state(p)
    assert core == pytest.approx(21.5 + p.heater_rise_K, abs=0.05) and 0.0 < tdc < 3.3 and tac == 1.65
    core, tdc, tac = thermal.steady_state(p, {"heater_failed": True})
    assert core == pytest.approx(21.5, abs=0.5) and 0.0 < tdc < 3.3 and tac == 1.65

"""A unit's own thermistor (issue 10.1): the thermal model uses ``thermistor_r25_ohm`` and ``thermistor_beta_K``,
while the published TDC conversion (D eq. 4.4) keeps the nominal part's constants, so a unit whose thermistor
differs reads a slightly wrong temperature through it."""

import numpy as np
import pytest

from emulator import conversions as conv
from emulator import thermal
from emulator.channels import channel_index
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.units import unit

pytestmark = pytest.mark.unit


def divider_V(r_ohm: float) -> float:
    """The TDC divider's output (SENSOR.md §4): 1.1 · 10 V · 30 kΩ / (R + 30 kΩ)."""
    return 1.1 * 10.0 * 30e3 / (r_ohm + 30e3)


def resting_tdc_code(p: SensorParams) -> float:
    s = Sensor(params=p, channels_read=["TDC"], noise=NoiseSources.none())
    return float(s.analog(np.array([channel_index("TDC")]), np.array([0.5]))[0] / conv.ADC_LSB_V)


def test_nominal_thermistor_is_470k_4025K_and_resting_tdc_unchanged():
    p = SensorParams()
    assert float(thermal.thermistor_ohm(25.0, p)) == pytest.approx(470e3, rel=1e-12)
    assert float(thermal.thermistor_ohm(25.0)) == float(thermal.thermistor_ohm(25.0, p))
    core, tdc_V, _ = thermal.steady_state(p)
    bead = thermal.ThermalModel(p, thermal.ThermalEvents([]), seed=0).x[thermal.BEAD]
    # the published conversion reads the nominal unit's bead temperature (its constants are rounded: 1e-3 K)
    assert float(conv.tdc_to_celsius(tdc_V / 3.3 * 4095)) == pytest.approx(bead, abs=1e-3)
    assert resting_tdc_code(p) == pytest.approx(tdc_V / conv.ADC_LSB_V, abs=1e-6)


@pytest.mark.parametrize("r25_factor", [1.01, 0.99])
def test_a_units_r25_moves_resting_tdc_by_what_its_resistance_predicts(r25_factor):
    nominal = SensorParams()
    other = nominal.replace(thermistor_r25_ohm=470e3 * r25_factor)
    _, v0, _ = thermal.steady_state(nominal)
    _, v1, _ = thermal.steady_state(other)
    bead = thermal.ThermalModel(nominal, thermal.ThermalEvents([]), seed=0).x[thermal.BEAD]
    r0 = 470e3 * np.exp(4025.0 / (bead + 273.15) - 4025.0 / 298.15)
    predicted = divider_V(r0 * r25_factor) - divider_V(r0)  # the bead's own temperature barely moves (self-heating)
    assert abs(predicted) > 5e-3  # ~6 mV: about 8 codes
    assert v1 - v0 == pytest.approx(predicted, rel=0.01)
    # through the ADC the same shift, in codes
    assert resting_tdc_code(other) - resting_tdc_code(nominal) == pytest.approx(predicted / conv.ADC_LSB_V, rel=0.01)
    # the published conversion (nominal constants) reads the bead wrong by ln(R25'/R25) / (B/T²)
    misread = float(conv.tdc_to_celsius(v1 / 3.3 * 4095)) - float(conv.tdc_to_celsius(v0 / 3.3 * 4095))
    T = bead + 273.15
    assert misread == pytest.approx(-np.log(r25_factor) * T * T / 4025.0, rel=0.02)


def test_a_units_beta_changes_the_thermistor_curve_but_not_r25():
    p = SensorParams().replace(thermistor_beta_K=4025.0 * 1.03)
    assert float(thermal.thermistor_ohm(25.0, p)) == pytest.approx(470e3, rel=1e-12)
    assert float(thermal.thermistor_ohm(35.0, p)) == pytest.approx(
        470e3 * np.exp(4025.0 * 1.03 * (1 / 308.15 - 1 / 298.15)), rel=1e-12)
    assert thermal.steady_state(p)[1] != thermal.steady_state(SensorParams())[1]


def test_drawn_units_read_their_own_thermistor():
    for seed in (1, 2, 3):
        u = unit(seed)
        assert u.params.thermistor_r25_ohm != 470e3
        assert thermal.steady_state(u.params)[1] != thermal.steady_state(SensorParams())[1]


def test_the_running_network_reads_the_units_thermistor_as_the_shortcut_does():
    """The network advanced in time (as under any thermal event) and the settled shortcut agree for a unit."""
    p = SensorParams().replace(thermistor_r25_ohm=470e3 * 1.01, thermistor_beta_K=4025.0 * 0.98)
    model = thermal.ThermalModel(p, thermal.ThermalEvents([]), seed=0, noise=False)
    tdc = model.values_at(np.array([0.0, 2.0, 5.0]))[:, 1]
    assert tdc == pytest.approx(thermal.steady_state(p)[1], abs=1e-6)  # 1e-6 V: ~0.001 code
    assert abs(tdc[-1] - thermal.steady_state(SensorParams())[1]) > 5e-3


def test_self_heating_is_the_units_own_thermistors():
    p = SensorParams().replace(thermistor_r25_ohm=470e3 * 1.01)
    model = thermal.ThermalModel(p, thermal.ThermalEvents([]), seed=0, noise=False)
    r = 470e3 * 1.01 * np.exp(4025.0 / 308.15 - 4025.0 / 298.15)
    v = 10.0 * r / (r + 30e3)
    assert model._self_heating_W(35.0) == pytest.approx(v * v / r, rel=1e-9)

"""Every physical parameter of the emulated sensor, in SI units, with its source.

Each field carries ``unit``, an allowed ``range`` and ``source`` metadata:
``D`` (dissertation), ``P`` (vendor protocol) or ``model`` (a model choice the
sources leave open — see SENSOR.md).  Scene files override fields by name and
are validated against these ranges before anything runs.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from emulator.conversions import ADC_LSB_V

BOLTZMANN_J_PER_K = 1.380649e-23
ZERO_CELSIUS_K = 273.15


def _p(default, unit, lo, hi, source, doc):
    return field(default=default, metadata={"unit": unit, "range": (lo, hi), "source": source, "doc": doc})


@dataclass(frozen=True)
class SensorParams:
    """Parameters of one sensor. Units are in the field names or metadata."""

    # --- fluid and skin (SENSOR.md §1) -------------------------------------------------
    inflation_volume_mL: float = _p(0.5, "mL", 0.05, 1.2, "D", "fluid volume between skin and core (~0.5 mL)")
    resting_pressure_Pa_per_mL: float = _p(
        12e3, "Pa/mL", 0.0, 1e5, "model", "resting fluid pressure rise per mL of inflation (repeatable, D ch. 4)")
    resting_pressure_exponent: float = _p(
        1.5, "1", 1.0, 3.0, "model", "resting pressure grows as volume^exponent (skin stiffens as it stretches)")
    force_per_pdc_bit_N: float = _p(
        0.0115, "N", 1e-4, 1.0, "D", "contact force per PDC bit below the knee (11.5 mN/bit, R² = 0.995)")
    force_knee_N: float = _p(2.0, "N", 0.1, 20.0, "D", "force where the skin meets the core and the slope falls")
    force_slope_above_knee: float = _p(
        0.25, "1", 0.0, 1.0, "model", "pressure slope above the knee as a fraction of the slope below")
    force_knee_width_N: float = _p(0.08, "N", 0.01, 2.0, "model", "smoothness of the transition at the knee")
    resonance_Hz: float = _p(330.0, "Hz", 200.0, 350.0, "D", "skin/fluid resonance at nominal inflation")
    resonance_Hz_per_mL: float = _p(
        150.0, "Hz/mL", 0.0, 1000.0, "model", "resonance shift with inflation volume away from 0.5 mL")
    resonance_decay_s: float = _p(0.020, "s", 0.002, 0.2, "D", "decay time constant of impact ringing")
    displacement_to_pressure_Pa_per_m: float = _p(
        3.17e6, "Pa/m", 1e4, 1e9, "model",
        "static skin displacement -> fluid pressure (force slope x ~1 N/mm fingertip stiffness)")
    displacement_zero_Hz: float = _p(
        500.0, "Hz", 50.0, 1e4, "model", "zero of the displacement path (direct transmission through the liquid)")
    impact_restitution: float = _p(0.3, "1", 0.0, 1.0, "model", "coefficient of restitution of a sphere on the skin")
    impact_contact_s: float = _p(0.4e-3, "s", 1e-5, 5e-3, "model", "contact duration of a sphere impact (half-sine)")
    duct_resonance_Hz: float = _p(
        18.7e3, "Hz", 5e3, 1e5, "D", "closed-tube resonance of the 2 cm fluid duct, v/(4L) (reference profile only)")
    duct_quality_factor: float = _p(5.0, "1", 0.5, 100.0, "model", "quality factor of the duct resonance")

    # --- piezoresistive bridge (SENSOR.md §3) ------------------------------------------
    bridge_excitation_V: float = _p(10.0, "V", 1.0, 15.0, "D", "bridge supply")
    bridge_sensitivity_V_per_V_Pa: float = _p(0.218e-6, "V/(V·Pa)", 1e-8, 1e-5, "D", "0.218 mV/V·kPa")
    bridge_resistance_ohm: float = _p(5e3, "Ω", 100.0, 1e6, "D", "output resistance (Johnson noise source)")
    bridge_temperature_C: float = _p(35.0, "°C", -20.0, 80.0, "D", "bridge temperature: the heated core, ~35 °C")
    bridge_reference_temperature_C: float = _p(
        35.0, "°C", -20.0, 80.0, "model", "temperature at which offset and span equal their nominal values")
    bridge_offset_V_per_V: float = _p(0.0, "V/V", -0.01, 0.01, "model", "zero-pressure offset at the reference temperature")
    bridge_offset_drift_V_per_V_K: float = _p(
        -1.0e-6, "V/(V·K)", -1e-4, 1e-4, "model", "offset drift (uncompensated transducer)")
    bridge_span_drift_per_K: float = _p(
        -2.0e-3, "1/K", -0.02, 0.02, "model", "relative sensitivity drift (uncompensated transducer)")

    # --- analog front end (SENSOR.md §3) -----------------------------------------------
    stage1_gain: float = _p(10.0, "V/V", 1.0, 1000.0, "D", "first-stage gain")
    stage1_lowpass_Hz: float = _p(1040.0, "Hz", 100.0, 5000.0, "D", "anti-aliasing low-pass (2nd-order Butterworth)")
    stage1_bias_V: float = _p(0.5, "V", 0.0, 3.3, "model", "positive bias of the PDC output so it never saturates low")
    stage2_gain: float = _p(99.1, "V/V", 1.0, 1000.0, "D", "second-stage gain")
    stage2_highpass_Hz: float = _p(10.0, "Hz", 0.1, 100.0, "D", "lower edge of the PAC band (1st-order)")
    stage2_bias_V: float = _p(1.65, "V", 0.0, 3.3, "D", "PAC mid-scale bias")
    supply_rail_V: float = _p(3.3, "V", 1.0, 5.0, "D", "op-amp output swing 0..rail")
    amp_voltage_noise_V_per_rtHz: float = _p(
        0.39e-6 / math.sqrt(1024.0), "V/√Hz", 0.0, 1e-6, "D", "first-stage input voltage noise: 0.39 µV over 1024 Hz")
    amp_current_noise_A_per_rtHz: float = _p(
        4.8e-12 / math.sqrt(1024.0), "A/√Hz", 0.0, 1e-9, "D", "first-stage input current noise: 4.8 pA over 1024 Hz")
    stage2_voltage_noise_V_per_rtHz: float = _p(
        0.39e-6 / math.sqrt(1024.0), "V/√Hz", 0.0, 1e-6, "D", "second-stage input noise (reference profile only)")

    # --- ADC (SENSOR.md §2) ------------------------------------------------------------
    adc_conversion_s: float = _p(
        5e-6, "s", 1e-7, 1e-4, "model",
        "ADC acquisition and conversion window after a command; SPI clocking inside it couples into the sample")
    adc_noise_rms_bits: float = _p(
        1.13, "LSB", 0.0, 20.0, "model",
        "ADC input noise; with quantization and mains hum it makes the measured 1.4 bits RMS at rest")

    # --- extrinsic noise (SENSOR.md §3) ------------------------------------------------
    mains_frequency_Hz: float = _p(60.0, "Hz", 40.0, 70.0, "D", "mains frequency (60 Hz in the source lab)")
    mains_amplitude_V: float = _p(
        0.516e-6, "V", 0.0, 1e-3, "model",
        "hum amplitude at the first-stage input; gives the 0.2 bits² largest 2 Hz band of PAC at rest")
    spi_coupling_rms_V: float = _p(
        4.0e-3, "V", 0.0, 0.1, "model", "ADC-input disturbance when a conversion overlaps SPI clocking")

    # --- resting levels of channels modelled by the thermal/electrode issue -----------
    resting_tdc_code: int = _p(2560, "code", 0, 4095, "model", "TDC at a settled heater (placeholder level)")
    resting_tac_code: int = _p(2048, "code", 0, 4095, "model", "TAC with no heat flux (placeholder level)")
    resting_electrode_code: int = _p(2900, "code", 0, 4095, "model", "E1..E19 with an undeformed skin (placeholder)")

    # ------------------------------------------------------------------------------
    @property
    def bridge_temperature_K(self) -> float:
        return self.bridge_temperature_C + ZERO_CELSIUS_K

    @property
    def resonance_at_inflation_Hz(self) -> float:
        """Resonance moved by inflation and kept within the published 200–350 Hz."""
        f = self.resonance_Hz + self.resonance_Hz_per_mL * (self.inflation_volume_mL - 0.5)
        return min(max(f, 200.0), 350.0)

    @property
    def resting_pressure_Pa(self) -> float:
        """Resting (DC) fluid pressure from the inflation volume."""
        return self.resting_pressure_Pa_per_mL * self.inflation_volume_mL ** self.resting_pressure_exponent

    @property
    def bridge_span_V_per_Pa(self) -> float:
        """Bridge output per Pa at its present temperature."""
        dT = self.bridge_temperature_C - self.bridge_reference_temperature_C
        return self.bridge_excitation_V * self.bridge_sensitivity_V_per_V_Pa * (1.0 + self.bridge_span_drift_per_K * dT)

    @property
    def bridge_offset_V(self) -> float:
        dT = self.bridge_temperature_C - self.bridge_reference_temperature_C
        return self.bridge_excitation_V * (self.bridge_offset_V_per_V + self.bridge_offset_drift_V_per_V_K * dT)

    @property
    def johnson_noise_V_per_rtHz(self) -> float:
        """√(4kTR) of the bridge output resistance at the bridge temperature."""
        return math.sqrt(4.0 * BOLTZMANN_J_PER_K * self.bridge_temperature_K * self.bridge_resistance_ohm)

    @property
    def force_to_pressure_Pa_per_N(self) -> float:
        """Mechanical slope force -> fluid pressure, fixed by the published force per PDC bit.

        Uses the bridge span at its reference temperature: the mechanics does not drift with the bridge.
        """
        nominal_pdc_V_per_Pa = self.bridge_excitation_V * self.bridge_sensitivity_V_per_V_Pa * self.stage1_gain
        pdc_Pa_per_bit = ADC_LSB_V / nominal_pdc_V_per_Pa
        return pdc_Pa_per_bit / self.force_per_pdc_bit_N

    @property
    def pac_V_per_Pa(self) -> float:
        return self.bridge_span_V_per_Pa * self.stage1_gain * self.stage2_gain

    @property
    def pdc_V_per_Pa(self) -> float:
        return self.bridge_span_V_per_Pa * self.stage1_gain

    def replace(self, **changes) -> "SensorParams":
        """A copy with some fields changed, each checked against its range."""
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise ValueError(f"unknown sensor parameter(s): {', '.join(sorted(unknown))}")
        for name, value in changes.items():
            check_parameter(name, value, where=f"sensor.{name}")
        return dataclasses.replace(self, **changes)


PARAMETER_FIELDS = {f.name: f for f in dataclasses.fields(SensorParams)}


def check_parameter(name: str, value, where: str) -> None:
    """Raise ValueError naming ``where``, the value and the allowed range if ``value`` is out of range."""
    meta = PARAMETER_FIELDS[name].metadata
    lo, hi = meta["range"]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{where} = {value!r}: must be a finite number in {meta['unit']} ({lo} to {hi})")
    if not lo <= value <= hi:
        raise ValueError(f"{where} = {value!r} {meta['unit']}: allowed range is {lo} to {hi} {meta['unit']}")

"""A mutation catalogue: deliberate faults in the physics, the protocol, the firmware and the host, each of which
some test must catch.

Each :class:`Mutant` names a file, an exact snippet of it (which must occur exactly once), its replacement and
the pytest selection that should fail once the snippet is replaced.  Mutants are applied to a *scratch copy*
of the tree (the git-tracked and untracked-but-not-ignored files of the working tree, copied to a temporary
folder), never to the checkout itself; the selected tests run there with ``cwd`` and ``PYTHONPATH`` set to the
copy, so the copy's modules are the ones imported (checked before anything runs: the editable install in
``.venv`` appends its finder to ``sys.meta_path``, after ``PYTHONPATH``), and with ``PYTHONDONTWRITEBYTECODE``
so a mutation of the same length written within the same second never meets a stale ``.pyc``.  C sources
are rebuilt because the bench caches native builds by the hash of their sources.

A result is *caught* (the tests failed), *survived* (they passed: a blind spot — write the missing test) or
*error* (the snippet is gone, the tests could not be collected, or they timed out).  Before the mutants, the
union of their selections runs once unmutated (the baseline): a selection that fails without any mutation
would make every mutant look caught.

    python -m bench.verification.mutants                 # the whole catalogue: table, exit 1 unless all caught
    python -m bench.verification.mutants --list          # names, files, what each breaks
    python -m bench.verification.mutants --only adc-reference-3v0 --json
    python -m bench.verification.mutants --fast          # the sample that also runs in the test suite
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Mutant:
    """One deliberate fault: replace ``original`` (exactly one occurrence in ``file``) by ``replacement``."""

    name: str
    area: str
    file: str  # relative to the repository root
    original: str
    replacement: str
    tests: tuple[str, ...]  # pytest node ids or paths, relative to the repository root
    what: str  # the fault, in words


@dataclass
class Result:
    name: str
    area: str
    file: str
    status: str  # caught, survived, error
    seconds: float
    detail: str = ""

    def as_dict(self) -> dict:
        return asdict(self)


# --- test selections used below -------------------------------------------------------------------------
_DOC = "emulator/tests/test_documented_behaviour.py"
_PROTO = "emulator/tests/test_parity_and_timing.py"
_MODEL = "emulator/tests/test_model.py"
_FILTERS = "emulator/tests/test_filters.py"
_THERMAL = "emulator/tests/test_thermal_electrodes.py"
_FW_DOC = "firmware_tests/tests/test_firmware_documented.py"
_CLI = "bench/tests/test_cli_and_runs.py"
_SLIDE = "emulator/tests/test_sliding.py"
_RIG = "bench/tests/test_texture_rig.py"
_LIVE = "emulator/tests/test_thermal_live_contact.py"
_EXP = "bench/tests/test_experiment.py"
_SOLVER = "emulator/tests/test_friction_solver.py"

CATALOGUE: list[Mutant] = [
    # --- physical constants -------------------------------------------------------------------------
    Mutant("boltzmann-x10", "constants", "emulator/params.py",
           "BOLTZMANN_J_PER_K = 1.380649e-23", "BOLTZMANN_J_PER_K = 1.380649e-22",
           (f"{_MODEL}::test_johnson_noise_follows_sqrt_4kTR",), "Boltzmann's constant ten times too large"),
    Mutant("johnson-2kTR", "noise", "emulator/params.py",
           "math.sqrt(4.0 * BOLTZMANN_J_PER_K", "math.sqrt(2.0 * BOLTZMANN_J_PER_K",
           (f"{_MODEL}::test_johnson_noise_follows_sqrt_4kTR", f"{_DOC}::test_each_noise_source_matches_the_budget"),
           "Johnson noise from √(2kTR) instead of √(4kTR)"),
    Mutant("bridge-resistance-50k", "constants", "emulator/params.py",
           'bridge_resistance_ohm: float = _p(5e3,', 'bridge_resistance_ohm: float = _p(50e3,',
           (f"{_MODEL}::test_johnson_noise_follows_sqrt_4kTR",), "bridge output resistance 50 kΩ instead of 5 kΩ"),
    Mutant("bridge-sensitivity-half", "constants", "emulator/params.py",
           "bridge_sensitivity_V_per_V_Pa: float = _p(0.218e-6,", "bridge_sensitivity_V_per_V_Pa: float = _p(0.109e-6,",
           (f"{_MODEL}::test_calibrator_pressure_reaches_pdc_at_the_published_scale",
            f"{_DOC}::test_pac_scale_is_0_37_Pa_per_bit"),
           "bridge sensitivity halved (the force claim still reads 11.5 mN/bit: it is a read-back)"),
    Mutant("bridge-excitation-5V", "constants", "emulator/params.py",
           'bridge_excitation_V: float = _p(10.0,', 'bridge_excitation_V: float = _p(5.0,',
           (f"{_MODEL}::test_calibrator_pressure_reaches_pdc_at_the_published_scale",),
           "bridge excited at 5 V instead of 10 V"),
    Mutant("stage1-gain-11", "constants", "emulator/params.py",
           "stage1_gain: float = _p(10.0,", "stage1_gain: float = _p(11.0,",
           (f"{_MODEL}::test_calibrator_pressure_reaches_pdc_at_the_published_scale",),
           "first-stage gain 11 instead of 10"),
    Mutant("stage2-gain-90", "constants", "emulator/params.py",
           "stage2_gain: float = _p(99.1,", "stage2_gain: float = _p(90.0,",
           (f"{_DOC}::test_pac_scale_is_0_37_Pa_per_bit",), "second-stage gain 90 instead of 99.1"),
    Mutant("pac-bias-1v5", "constants", "emulator/params.py",
           'stage2_bias_V: float = _p(1.65,', 'stage2_bias_V: float = _p(1.5,',
           (f"{_MODEL}::test_full_frame_channels_all_convert",), "PAC biased at 1.5 V instead of mid-scale 1.65 V"),
    Mutant("skin-direct-stiffness-x4", "constants", "emulator/params.py",
           "skin_direct_stiffness_N_per_m: float = _p(\n        160.0,",
           "skin_direct_stiffness_N_per_m: float = _p(\n        640.0,",
           (f"{_DOC}::test_a_1_N_press_raises_PDC_by_87_bits",),
           "the skin carries four times its share of the load (the fluid's share falls: ~15 mN per PDC bit)"),
    Mutant("force-knee-4N", "constants", "emulator/params.py",
           "force_knee_N: float = _p(2.0,", "force_knee_N: float = _p(4.0,",
           (f"{_MODEL}::test_force_curve_is_linear_below_the_knee_and_flattens_above",), "knee at 4 N instead of 2 N"),
    Mutant("heater-rise-5K", "thermal", "emulator/params.py",
           "heater_rise_K: float = _p(10.0,", "heater_rise_K: float = _p(5.0,",
           (f"{_THERMAL}::test_heater_holds_the_core_10K_above_ambient_and_warms_up_over_minutes",),
           "heaters hold the core 5 K above ambient instead of 10 K"),
    # --- ADC ------------------------------------------------------------------------------------------
    Mutant("adc-11-bits", "adc", "emulator/conversions.py", "ADC_BITS = 12", "ADC_BITS = 11",
           (f"{_DOC}::test_adc_rounds_to_the_nearest_code_and_clips_at_the_rails",), "an 11-bit ADC"),
    Mutant("adc-reference-3v0", "adc", "emulator/conversions.py",
           "ADC_FULL_SCALE_V = 3.3", "ADC_FULL_SCALE_V = 3.0",
           (f"{_MODEL}::test_calibrator_pressure_reaches_pdc_at_the_published_scale",), "ADC reference 3.0 V"),
    Mutant("adc-truncates", "adc", "emulator/adc.py",
           "    c += 0.5\n    np.floor(c, out=c)", "    c += 0.0\n    np.floor(c, out=c)",
           (f"{_DOC}::test_adc_rounds_to_the_nearest_code_and_clips_at_the_rails",),
           "the ADC truncates instead of rounding to the nearest code"),
    Mutant("adc-clips-at-4096", "adc", "emulator/adc.py",
           "np.clip(c, 0, ADC_CODES - 1, out=c)", "np.clip(c, 0, ADC_CODES, out=c)",
           (f"{_DOC}::test_adc_rounds_to_the_nearest_code_and_clips_at_the_rails",),
           "the ADC clips at 4096 (wraps to 0 in 12 bits)"),
    Mutant("adc-noise-doubled", "noise", "emulator/adc.py",
           "params.adc_noise_rms_bits * ADC_LSB_V if noise", "2 * params.adc_noise_rms_bits * ADC_LSB_V if noise",
           ("emulator/tests/test_channel_noise.py::test_adc_input_noise_is_its_parameter_on_every_channel",),
           "ADC input noise twice its parameter"),
    # --- filters: orders and corners ------------------------------------------------------------------
    Mutant("stage1-lowpass-1st-order", "filters", "emulator/filters.py",
           'return signal.butter(2, 2 * np.pi * f_hz', 'return signal.butter(1, 2 * np.pi * f_hz',
           (f"{_DOC}::test_pdc_front_end_is_a_2nd_order_butterworth_at_1040_Hz",),
           "anti-alias filter of order 1 instead of 2"),
    Mutant("stage1-corner-2000Hz", "filters", "emulator/params.py",
           "stage1_lowpass_Hz: float = _p(1040.0,", "stage1_lowpass_Hz: float = _p(2000.0,",
           (f"{_DOC}::test_pdc_front_end_is_a_2nd_order_butterworth_at_1040_Hz",),
           "anti-alias corner at 2000 Hz instead of 1040 Hz"),
    Mutant("stage2-highpass-1Hz", "filters", "emulator/params.py",
           "stage2_highpass_Hz: float = _p(10.0,", "stage2_highpass_Hz: float = _p(1.0,",
           (f"{_DOC}::test_pac_band_starts_with_a_1st_order_10_Hz_high_pass",), "PAC high-pass at 1 Hz instead of 10 Hz"),
    Mutant("highpass-2nd-order", "filters", "emulator/filters.py",
           "return np.array([0.0]), np.array([-2 * np.pi * f_hz]), 1.0",
           "return np.array([0.0, 0.0]), np.array([-2 * np.pi * f_hz, -2 * np.pi * f_hz]), 1.0",
           (f"{_DOC}::test_pac_band_starts_with_a_1st_order_10_Hz_high_pass",),
           "the high-passes (PAC 10 Hz, TAC 0.45 Hz) of order 2 instead of 1"),
    Mutant("no-prewarping", "filters", "emulator/filters.py",
           "out[ok] = roots[ok] / mag[ok] * (2.0 * fs * np.tan(mag[ok] / (2.0 * fs)))", "out[ok] = roots[ok]",
           (f"{_FILTERS}::test_prewarping_puts_the_1040Hz_corner_where_it_belongs_near_nyquist",),
           "prewarping silently does nothing"),
    Mutant("tdc-bandwidth-2Hz", "filters", "emulator/params.py",
           "tdc_bandwidth_Hz: float = _p(22.6,", "tdc_bandwidth_Hz: float = _p(2.26,",
           (f"{_DOC}::test_TDC_bandwidth_is_22_6_Hz",), "TDC bandwidth 2.26 Hz instead of 22.6 Hz"),
    Mutant("tdc-bandwidth-45Hz", "filters", "emulator/params.py",
           "tdc_bandwidth_Hz: float = _p(22.6,", "tdc_bandwidth_Hz: float = _p(45.0,",
           (f"{_DOC}::test_TDC_bandwidth_is_22_6_Hz",), "TDC bandwidth 45 Hz instead of 22.6 Hz"),
    Mutant("tac-highpass-5Hz", "filters", "emulator/params.py",
           "tac_highpass_Hz: float = _p(0.45,", "tac_highpass_Hz: float = _p(5.0,",
           (f"{_DOC}::test_TAC_is_98_times_a_0_45_Hz_high_pass_of_TDC",),
           "TAC high-pass at the text's 5 Hz instead of Table 4-1's 0.45 Hz"),
    Mutant("tac-gain-49", "thermal", "emulator/thermal.py", "TAC_GAIN = 98.0", "TAC_GAIN = 49.0",
           (f"{_DOC}::test_TAC_is_98_times_a_0_45_Hz_high_pass_of_TDC",), "TAC gain 49 instead of 98"),
    Mutant("electrode-bandwidth-5Hz", "filters", "emulator/params.py",
           "electrode_bandwidth_Hz: float = _p(100.0,", "electrode_bandwidth_Hz: float = _p(5.0,",
           (f"{_DOC}::test_electrode_bandwidth_is_100_Hz",), "electrode bandwidth 5 Hz instead of 100 Hz"),
    Mutant("electrode-bandwidth-300Hz", "filters", "emulator/params.py",
           "electrode_bandwidth_Hz: float = _p(100.0,", "electrode_bandwidth_Hz: float = _p(300.0,",
           (f"{_DOC}::test_electrode_bandwidth_is_100_Hz",), "electrode bandwidth 300 Hz instead of 100 Hz"),
    # --- resonance, impacts, displacement ------------------------------------------------------------
    Mutant("resonance-250Hz", "mechanics", "emulator/params.py",
           "resonance_Hz: float = _p(330.0,", "resonance_Hz: float = _p(250.0,",
           (f"{_DOC}::test_an_impact_rings_at_330_Hz_with_a_20_ms_decay",), "skin/fluid resonance at 250 Hz"),
    Mutant("resonance-decay-40ms", "mechanics", "emulator/params.py",
           "resonance_decay_s: float = _p(0.020,", "resonance_decay_s: float = _p(0.040,",
           (f"{_DOC}::test_an_impact_rings_at_330_Hz_with_a_20_ms_decay",), "ringing decays in 40 ms"),
    Mutant("resonance-sigma-doubled", "mechanics", "emulator/filters.py",
           "sigma = 1.0 / decay_s", "sigma = 2.0 / decay_s",
           (f"{_FILTERS}::test_resonance_rings_at_its_frequency_with_its_decay",), "envelope decays twice as fast"),
    Mutant("impulse-x2.5", "mechanics", "emulator/stimuli.py",
           "return self.impulse_Ns * np.interp(x, _HERTZ_X, _HERTZ_C)",
           "return 2.5 * self.impulse_Ns * np.interp(x, _HERTZ_X, _HERTZ_C)",
           (f"{_MODEL}::test_force_pulses_deliver_the_same_impulse_on_any_grid",
            f"{_DOC}::test_an_impact_rings_with_the_amplitude_its_impulse_predicts"),
           "a sphere delivers 2.5 times its impulse"),
    Mutant("restitution-ignored", "mechanics", "emulator/stimuli.py",
           "self.impact_speed_m_per_s * (1.0 + self.restitution)", "self.impact_speed_m_per_s * (1.0 + 0.0)",
           (f"{_DOC}::test_the_impact_impulse_is_m_v_1_plus_e",), "the bounce (1 + e) left out of the impulse"),
    Mutant("scene-drops-ignore-the-unit", "mechanics", "bench/scenes/scene.py",
           "sphere_drop_on(params, t, mass, height, sphere=name, radius_m=radius)",
           "sphere_drop_on(SensorParams(), t, mass, height, sphere=name, radius_m=radius)",
           (f"{_DOC}::test_the_impact_impulse_is_m_v_1_plus_e",),
           "scenes drop spheres on the nominal sensor (its restitution and skin), not the scene's own"),
    Mutant("hertz-contact-x10", "mechanics", "emulator/mechanics.py",
           "return 2.9432 * d_max", "return 29.432 * d_max",
           (f"{_DOC}::test_an_impact_rings_with_the_amplitude_its_impulse_predicts",
            "emulator/tests/test_skin_mechanics.py::test_hertz_duration_scaling_and_energy",
            "bench/tests/test_impact_regimes.py::test_d_spheres_at_their_thresholds_hit_with_pulses_short_against_the_period"),
           "Hertz contacts last ten times longer than the contact mechanics gives"),
    Mutant("impulse-proportional-to-energy", "mechanics", "emulator/stimuli.py",
           "return self.mass_kg * self.impact_speed_m_per_s * (1.0 + self.restitution)",
           "return self.mass_kg * self.impact_speed_m_per_s ** 2 * (1.0 + self.restitution)",
           ("bench/tests/test_impact_regimes.py::test_in_d_s_regime_the_threshold_is_a_momentum_not_a_force_or_an_energy",),
           "a drop's impulse grows with its energy, not its momentum (the energy/momentum deviation would then pass)"),
    Mutant("drops-fall-in-vacuum", "mechanics", "emulator/stimuli.py",
           "return fall_speed_m_per_s(self.mass_kg, self.sphere_radius_m, self.height_m, self.air_density_kg_per_m3,",
           "return fall_speed_m_per_s(self.mass_kg, self.sphere_radius_m, self.height_m, 0.0,",
           ("emulator/tests/test_falling_spheres.py",),
           "spheres fall without air: a small sphere from 10 m lands at √(2·g·h), three times its terminal speed"),
    Mutant("stokes-drag-a-tenth", "mechanics", "emulator/mechanics.py",
           "return (24.0 / re + 2.6", "return (2.4 / re + 2.6",
           ("emulator/tests/test_falling_spheres.py",),
           "the sphere drag's viscous (Stokes) term a tenth of 24/Re: small spheres fall too fast"),
    Mutant("pac-highpass-100Hz", "chain", "emulator/params.py",
           "stage2_highpass_Hz: float = _p(10.0,", "stage2_highpass_Hz: float = _p(100.0,",
           ("bench/tests/test_impact_regimes.py::test_pulses_long_against_the_period_make_the_threshold_follow_energy",),
           "the PAC band's lower edge at 100 Hz differentiates slow contact pulses"),
    Mutant("displacement-gain-x10", "mechanics", "emulator/mechanics.py",
           "pressure_per_displacement_Pa_per_m=kf / A,", "pressure_per_displacement_Pa_per_m=10 * kf / A,",
           (f"{_DOC}::test_skin_displacement_reaches_the_liquid_with_the_documented_gain_and_zero",),
           "skin displacement -> pressure ten times too strong"),
    Mutant("displacement-zero-5kHz", "mechanics", "emulator/params.py",
           "        500.0, \"Hz\", 50.0, 1e4,", "        5000.0, \"Hz\", 50.0, 1e4,",
           (f"{_DOC}::test_skin_displacement_reaches_the_liquid_with_the_documented_gain_and_zero",),
           "direct liquid path's zero at 5 kHz instead of 500 Hz"),
    # --- noise sources -------------------------------------------------------------------------------
    Mutant("white-noise-bandwidth-fs", "noise", "emulator/transducer.py",
           "self.sigma = density * np.sqrt(fs / 2.0)", "self.sigma = density * np.sqrt(fs)",
           (f"{_DOC}::test_each_noise_source_matches_the_budget",),
           "grid white noise sized for a bandwidth of fs instead of fs/2"),
    Mutant("amplifier-noise-x2", "noise", "emulator/params.py",
           "0.39e-6 / math.sqrt(1024.0), \"V/√Hz\", 0.0, 1e-6, \"D\", \"first-stage",
           "0.78e-6 / math.sqrt(1024.0), \"V/√Hz\", 0.0, 1e-6, \"D\", \"first-stage",
           (f"{_CLI}::test_noise_budget_json_reproduces_table_5_1",), "first-stage voltage noise doubled"),
    Mutant("hum-50Hz", "noise", "emulator/params.py",
           "mains_frequency_Hz: float = _p(60.0,", "mains_frequency_Hz: float = _p(50.0,",
           ("emulator/tests/test_channel_noise.py::test_hum_off_removes_fundamental_and_harmonics_only",),
           "50 Hz mains"),
    Mutant("hum-x10", "noise", "emulator/params.py",
           "        0.516e-6, \"V\"", "        5.16e-6, \"V\"",
           (f"{_DOC}::test_the_hum_fills_the_largest_2_Hz_band_with_0_2_bits2",), "hum ten times too strong"),
    Mutant("spi-coupling-off", "noise", "emulator/adc.py",
           "v[bus_active] += self.coupling_V", "v[bus_active] += 0.0 * self.coupling_V",
           ("emulator/tests/test_protocol.py::test_clocking_the_bus_during_a_conversion_couples_noise_into_the_sample",),
           "SPI clocking during a conversion couples nothing"),
    # --- multiplexer and electrodes ------------------------------------------------------------------
    Mutant("mux-memory-deleted", "electrodes", "emulator/electrodes.py",
           "a = np.exp(-p.mux_acquisition_s / p.mux_settling_s)", "a = 0.0 * np.exp(-p.mux_acquisition_s / p.mux_settling_s)",
           (f"{_DOC}::test_the_multiplexer_keeps_0_67_percent_of_the_previous_electrode",),
           "the multiplexer's hold node forgets the previous electrode (and injects nothing)"),
    Mutant("mux-settling-2us", "electrodes", "emulator/params.py",
           "mux_settling_s: float = _p(4e-6,", "mux_settling_s: float = _p(2e-6,",
           (f"{_DOC}::test_the_multiplexer_keeps_0_67_percent_of_the_previous_electrode",),
           "the hold node settles twice as fast"),
    Mutant("mux-injection-off", "electrodes", "emulator/electrodes.py",
           "self.mux_injection = a * p.mux_injection_V", "self.mux_injection = 0.0 * p.mux_injection_V",
           (f"{_DOC}::test_charge_injection_offsets_repeated_reads_of_one_electrode",), "no charge injection"),
    Mutant("electrode-load-20k", "electrodes", "emulator/params.py",
           "electrode_load_ohm: float = _p(10e3,", "electrode_load_ohm: float = _p(20e3,",
           (f"{_THERMAL}::test_impedance_round_trips_through_eq_4_1",), "20 kΩ electrode load instead of 10 kΩ"),
    Mutant("electrode-geometry-E10-moved", "electrodes", "fixtures/electrodes.csv",
           "E10,1.299,0.000,-4.330", "E10,2.299,0.000,-4.330",
           (f"{_DOC}::test_electrode_positions_are_the_published_table",), "E10 moved 1 mm along the finger"),
    Mutant("electrode-geometry-mirror-broken", "electrodes", "fixtures/electrodes.csv",
           "E12,-2.700,3.513,-3.670", "E12,-2.700,3.513,-3.570",
           (f"{_DOC}::test_electrode_positions_are_the_published_table",), "E12 no longer E2's mirror image"),
    Mutant("core-radius-6mm", "electrodes", "emulator/electrodes.py", "CORE_RADIUS_MM = 5.0", "CORE_RADIUS_MM = 6.0",
           (f"{_DOC}::test_electrode_positions_are_the_published_table",),
           "contacts placed on a 6 mm core instead of the 5 mm the electrode table implies"),
    # --- thermistor ----------------------------------------------------------------------------------
    Mutant("thermistor-B-3950", "thermal", "emulator/params.py",
           '4025.0, "K", 2000.0, 6000.0', '3950.0, "K", 2000.0, 6000.0',
           (f"{_THERMAL}::test_thermistor_is_470k_at_25C_and_the_divider_matches_the_published_conversion",),
           "thermistor B = 3950 K instead of 4025 K"),
    Mutant("thermistor-47k", "thermal", "emulator/params.py",
           '470e3, "Ω", 1e3, 1e7', '47e3, "Ω", 1e3, 1e7',
           (f"{_THERMAL}::test_thermistor_is_470k_at_25C_and_the_divider_matches_the_published_conversion",),
           "47 kΩ thermistor instead of 470 kΩ"),
    Mutant("divider-10k", "thermal", "emulator/thermal.py", "DIVIDER_OHM = 30e3", "DIVIDER_OHM = 10e3",
           (f"{_THERMAL}::test_thermistor_is_470k_at_25C_and_the_divider_matches_the_published_conversion",),
           "10 kΩ divider resistor instead of 30 kΩ"),
    Mutant("tdc-conversion-constant", "thermal", "emulator/conversions.py",
           "(155183.0 - 46555.0 * x) / x", "(155183.0 - 46000.0 * x) / x",
           (f"{_THERMAL}::test_thermistor_is_470k_at_25C_and_the_divider_matches_the_published_conversion",),
           "a wrong constant in the published TDC conversion (D eq. 4.4)"),
    # --- protocol: parity of each byte ----------------------------------------------------------------
    Mutant("response-byte0-even-parity", "parity", "emulator/spi/protocol.py",
           "hi = with_odd_parity(data >> 5).astype(np.uint16)", "hi = (with_odd_parity(data >> 5) ^ 1).astype(np.uint16)",
           ("emulator/tests/test_protocol.py::test_response_words_round_trip_every_code_with_odd_parity_and_zero_bits",),
           "response words leave with the first byte's parity even"),
    Mutant("response-byte1-no-parity", "parity", "emulator/spi/protocol.py",
           "lo = lo_data | (~_POPCOUNT[lo_data] & 1)", "lo = lo_data",
           ("emulator/tests/test_protocol.py::test_response_words_round_trip_every_code_with_odd_parity_and_zero_bits",),
           "response words leave without the second byte's parity bit"),
    Mutant("host-ignores-byte1-parity", "parity", "emulator/spi/protocol.py",
           "return value, ODD_PARITY_OK[b0] & ODD_PARITY_OK[b1]", "return value, ODD_PARITY_OK[b0] & True",
           (f"{_PROTO}::test_every_single_bit_error_in_a_response_word_is_flagged",
            f"{_PROTO}::test_the_host_sampler_flags_parity_faults_in_either_byte"),
           "the host decoder ignores the second byte's parity"),
    Mutant("host-ignores-byte0-parity", "parity", "emulator/spi/protocol.py",
           "return value, ODD_PARITY_OK[b0] & ODD_PARITY_OK[b1]", "return value, True & ODD_PARITY_OK[b1]",
           (f"{_PROTO}::test_every_single_bit_error_in_a_response_word_is_flagged",),
           "the host decoder ignores the first byte's parity"),
    Mutant("sampler-error-words-as-parity", "parity", "bench/running/sampler.py",
           "status[proto.is_error_word(words)] = STATUS_ERROR_WORD", "pass",
           (f"{_PROTO}::test_the_host_sampler_marks_error_words_as_error_words",),
           "the host sampler reports error words as parity errors"),
    Mutant("command-even-parity", "parity", "emulator/spi/protocol.py",
           "return with_odd_parity(0x40 | c)", "return with_odd_parity(0x40 | c) ^ 1",
           ("emulator/tests/test_protocol.py::test_every_sampling_command_has_odd_parity",),
           "sampling commands sent with even parity"),
    Mutant("sensor-accepts-even-commands", "parity", "emulator/spi/model.py",
           "        elif not proto.ODD_PARITY_OK[b0]:\n            self._prepare_word(err[\"parity\"], t)",
           "        elif False:\n            self._prepare_word(err[\"parity\"], t)",
           ("emulator/tests/test_spi_model.py::test_mosi_bit_flip_turns_a_command_into_a_parity_error",),
           "the sensor's transfer-level path accepts commands with even parity"),
    Mutant("firmware-ignores-byte1-parity", "parity", "firmware_tests/firmware/bt_bridge.c",
           "else if (!odd_parity(b0) || !odd_parity(b1))", "else if (!odd_parity(b0))",
           (f"{_FW_DOC}::test_the_firmware_flags_parity_faults_in_either_byte",),
           "the firmware ignores the second byte's parity"),
    Mutant("firmware-ignores-byte0-parity", "parity", "firmware_tests/firmware/bt_bridge.c",
           "else if (!odd_parity(b0) || !odd_parity(b1))", "else if (!odd_parity(b1))",
           (f"{_FW_DOC}::test_the_firmware_flags_parity_faults_in_either_byte",),
           "the firmware ignores the first byte's parity"),
    Mutant("firmware-command-even-parity", "parity", "firmware_tests/firmware/bt_bridge.c",
           "return odd_parity(b) ? b : (uint8_t)(b | 1);", "return odd_parity(b) ? (uint8_t)(b | 1) : b;",
           (f"{_FW_DOC}::test_the_firmware_samples_with_the_vendor_timing",),
           "the firmware sends sampling commands with even parity"),
    # --- CRC -----------------------------------------------------------------------------------------
    Mutant("firmware-crc-poly-8005", "crc", "firmware_tests/firmware/bt_bridge.c",
           "crc ^= (uint16_t)data[i] << 8;\n        for (int k = 0; k < 8; ++k) crc = (crc & 0x8000) ? (uint16_t)((crc << 1) ^ 0x1021)",
           "crc ^= (uint16_t)data[i] << 8;\n        for (int k = 0; k < 8; ++k) crc = (crc & 0x8000) ? (uint16_t)((crc << 1) ^ 0x8005)",
           (f"{_FW_DOC}::test_the_firmware_crc_is_ccitt_false",), "the firmware's CRC-16 with polynomial 0x8005"),
    Mutant("firmware-payload-crc-poly", "crc", "firmware_tests/firmware/bt_bridge.c",
           "crc ^= (uint16_t)payload[i] << 8;\n        for (int k = 0; k < 8; ++k) crc = (crc & 0x8000) ? (uint16_t)((crc << 1) ^ 0x1021)",
           "crc ^= (uint16_t)payload[i] << 8;\n        for (int k = 0; k < 8; ++k) crc = (crc & 0x8000) ? (uint16_t)((crc << 1) ^ 0x1201)",
           (f"{_FW_DOC}::test_the_firmware_samples_with_the_vendor_timing",),
           "the CRC over a frame's payload with a wrong polynomial"),
    Mutant("firmware-crc-init-0", "crc", "firmware_tests/firmware/bt_bridge.c",
           "uint16_t bt_crc16(const uint8_t *data, size_t n) {\n    uint16_t crc = 0xFFFF;",
           "uint16_t bt_crc16(const uint8_t *data, size_t n) {\n    uint16_t crc = 0x0000;",
           (f"{_FW_DOC}::test_the_firmware_crc_is_ccitt_false",), "the firmware's CRC-16 starts from 0"),
    Mutant("driver-crc-poly-8005", "crc", "bench/hosts/driver.py",
           "crc = ((crc << 1) ^ 0x1021) & 0xFFFF", "crc = ((crc << 1) ^ 0x8005) & 0xFFFF",
           (f"{_PROTO}::test_the_driver_crc_is_ccitt_false",), "the host driver's CRC-16 with polynomial 0x8005"),
    # --- timing rules --------------------------------------------------------------------------------
    Mutant("sensor-delay-45us", "timing", "emulator/spi/model.py",
           "SAMPLE_DELAY_TICKS = 50", "SAMPLE_DELAY_TICKS = 45",
           (f"{_PROTO}::test_the_50_us_rule_has_its_boundary_at_50_us",), "the sensor answers after 45 µs"),
    Mutant("sensor-delay-55us", "timing", "emulator/spi/model.py",
           "SAMPLE_DELAY_TICKS = 50", "SAMPLE_DELAY_TICKS = 55",
           (f"{_PROTO}::test_the_50_us_rule_has_its_boundary_at_50_us",), "the sensor needs 55 µs"),
    Mutant("host-delay-40us", "timing", "emulator/spi/protocol.py",
           "SAMPLE_DELAY_S = 50e-6", "SAMPLE_DELAY_S = 40e-6",
           (f"{_PROTO}::test_the_host_sampler_reads_every_slot_cleanly_with_the_vendor_timing",),
           "the host sampler reads 40 µs after the command"),
    Mutant("sampling-delay-6us", "timing", "emulator/spi/model.py",
           "CONVERSION_TICKS = 5", "CONVERSION_TICKS = 6",
           (f"{_PROTO}::test_the_5_us_sampling_delay_has_its_boundary_at_5_us",),
           "the ADC stays busy 6 µs after a sampling command"),
    Mutant("sampling-delay-3us", "timing", "emulator/spi/model.py",
           "CONVERSION_TICKS = 5", "CONVERSION_TICKS = 3",
           (f"{_PROTO}::test_the_5_us_sampling_delay_has_its_boundary_at_5_us",),
           "the ADC is ready again 3 µs after a sampling command"),
    Mutant("conversion-window-2us", "timing", "emulator/params.py",
           "        5e-6, \"s\", 1e-7, 1e-4, \"model\",", "        2e-6, \"s\", 1e-7, 1e-4, \"model\",",
           (f"{_PROTO}::test_clocking_within_5_us_of_a_sampling_command_disturbs_the_conversion",),
           "SPI clocking disturbs a conversion only within 2 µs instead of 5 µs"),
    Mutant("firmware-delay-40us", "timing", "firmware_tests/firmware/bt_bridge.c",
           "#define SAMPLE_DELAY_NS 50000u", "#define SAMPLE_DELAY_NS 40000u",
           (f"{_FW_DOC}::test_the_firmware_samples_with_the_vendor_timing",), "the firmware reads 40 µs after the command"),
    Mutant("firmware-slot-4kHz", "timing", "firmware_tests/firmware/bt_bridge.c",
           "uint32_t t = (uint32_t)((uint64_t)k * 1000000000u / 4400u);",
           "uint32_t t = (uint32_t)((uint64_t)k * 1000000000u / 4000u);",
           (f"{_FW_DOC}::test_the_firmware_samples_with_the_vendor_timing",), "the firmware's slots at 4 kHz"),
    Mutant("firmware-word-gap-short", "timing", "firmware_tests/firmware/bt_bridge.c",
           "#define WORD_NS 3750u", "#define WORD_NS 3000u",
           (f"{_FW_DOC}::test_the_firmware_samples_with_the_vendor_timing",),
           "the firmware starts the next word before the previous one ended"),
    # --- sliding: friction, skin, wear ----------------------------------------------------------------
    Mutant("skin-tangential-stiffness-x2", "sliding", "emulator/params.py",
           'skin_tangential_stiffness_N_per_m: float = _p(\n        1500.0,',
           'skin_tangential_stiffness_N_per_m: float = _p(\n        3000.0,',
           (f"{_SLIDE}::test_stick_then_slip_tangential_force_ramps_to_static_then_settles_at_kinetic",),
           "the skin twice as stiff tangentially (the stick-phase ramp doubles)"),
    Mutant("stribeck-inverted", "sliding", "emulator/friction.py",
           "return mu_k + (mu_s - mu_k) * math.exp(-r * r)", "return mu_s - (mu_s - mu_k) * math.exp(-r * r)",
           (f"{_SLIDE}::test_stick_then_slip_tangential_force_ramps_to_static_then_settles_at_kinetic",),
           "the Stribeck curve upside down (friction rises from kinetic to static with speed)"),
    Mutant("wear-power-factor-dropped", "sliding", "emulator/skin.py",
           "power = (normal_N * velocity_m_per_s / self.reference_power_W) ** self.wear_power_exponent",
           "power = 1.0",
           (f"{_SLIDE}::test_wear_grows_as_a_power_of_the_sliding_power_at_the_same_force_and_distance",
            "bench/tests/test_experiment.py::test_the_wear_law_meets_d_wear_observations_with_its_calibrated_knobs"),
           "wear no longer steep in sliding power: no wear boundary where D excluded the high-power movements"),
    Mutant("skin-replaced-at-half-height", "sliding", "bench/experiments/trials.py",
           "FIRST_VISIBLE_WEAR = Skin().first_visible_wear_fraction", "FIRST_VISIBLE_WEAR = 0.5",
           ("bench/tests/test_experiment.py::test_replace_at_sets_how_worn_a_skin_gets_before_it_is_replaced",
            "bench/tests/test_experiment.py::test_the_wear_law_meets_d_wear_observations_with_its_calibrated_knobs"),
           "the skin kept until half its ridge height is gone (D replaced it at the first visible wear): "
           "validation drifts from training"),
    Mutant("visible-flat-full-width", "sliding", "emulator/skin.py",
           "r, half = self.ridge_crest_radius_m, self.visible_flat_width_m / 2",
           "r, half = self.ridge_crest_radius_m, self.visible_flat_width_m",
           (f"{_SLIDE}::test_first_visible_wear_is_a_flat_of_0_1_mm_on_the_rounded_crest",),
           "the first visible flat taken as its half-width: the replacement threshold 4× too high"),
    Mutant("ridges-catch-when-stuck", "sliding", "emulator/friction.py",
           "catching = abs(vr_last) / (abs(vr_last) + CATCH_VELOCITY_M_PER_S)", "catching = 1.0",
           (f"{_RIG}::test_force_control_through_pdc_overshoots_by_the_descent_over_the_batch_and_latency",),
           "ridges load feature slopes even when the skin does not slip (a pressed finger feels slope forces)"),
    Mutant("thermal-live-reads-ahead", "thermal", "emulator/thermal.py",
           "int(np.ceil(t_max / self.dt - 1e-9))))", "int(np.ceil(t_max / self.dt - 1e-9)) + 5))",
           ("emulator/tests/test_thermal_live_contact.py::"
            "test_reading_TDC_fixes_the_motion_only_through_the_instants_read",),
           "a live thermal contact advances 50 ms past the instants asked for, reading the finger's depth ahead"),
    Mutant("thermal-live-touches-above-surface", "thermal", "emulator/thermal.py",
           "on[on] = load > 0\n                a = live_patch_area_m2(load[load > 0], self.p)",
           "on[on] = load >= 0\n                a = live_patch_area_m2(load[load >= 0], self.p)",
           ("emulator/tests/test_thermal_live_contact.py::test_a_finger_above_the_surface_changes_nothing_thermal",),
           "the commanded finger touches the texture thermally while still above it (load 0)"),
    Mutant("spread-check-keeps-the-trial", "exploration", "bench/experiments/exploration.py",
           "    n1 = n - 1  # trials left when one is held out", "    n1 = n  # trials left when one is held out",
           ("bench/tests/test_exploration.py::test_spread_check_sees_a_shift_of_the_validation_trials_and_nothing_else",),
           "the leave-one-out normals of the spread check keep the held-out trial's count"),
    Mutant("rig-stops-on-averaged-pdc", "sliding", "bench/rigs/texture_rig.py",
           "pdc_average_frames: int = 1", "pdc_average_frames: int = 3",
           (f"{_RIG}::test_force_control_at_the_lightest_movement",),
           "the stepper stops on a 3-frame PDC average (a frame more lag) instead of each reading, as D describes"),
    Mutant("thermal-live-stale-step", "thermal", "emulator/thermal.py",
           "x = _steps(phis[rows[r]], x, np.dot(gams[rows[r]], u), out[j:bounds[r + 1]])",
           "x = _steps(phis[rows[0]], x, np.dot(gams[rows[r]], u), out[j:bounds[r + 1]])",
           (f"{_LIVE}::test_the_commanded_finger_cools_the_fingertip_in_the_order_of_the_surfaces_effusivity",
            f"{_LIVE}::test_codes_do_not_depend_on_block_size_or_on_how_reads_are_cut",
            f"{_LIVE}::test_the_compiled_runs_are_numpys_steps_run_by_run"),
           "the live contact keeps the first patch's discretization after the patch grows"),
    Mutant("thermal-ambient-step-late", "thermal", "emulator/thermal.py",
           "ambient[times >= when] = value", "ambient[times > when] = value",
           (f"{_LIVE}::test_the_inputs_of_many_steps_at_once_are_each_steps_own",),
           "the live network takes an ambient step one step late"),
    Mutant("thermal-compiled-step-off", "thermal", "emulator/thermal.py",
           "x = np.dot(Phi, x) + gu", "x = np.dot(Phi, x) + gu * 1.0000001",
           (f"{_LIVE}::test_compiled_steps_are_numpys_steps_bit_for_bit",),
           "the compiled steps of the live network drift from numpy's"),
    Mutant("thermal-one-column-wrong", "thermal", "emulator/thermal.py",
           "return np.interp(times, ht, hv[:, column])", "return np.interp(times, ht, hv[:, min(column, 1)])",
           (f"{_LIVE}::test_one_column_of_the_thermal_outputs_is_that_column_of_all_three",),
           "TAC read alone is read as TDC"),
    Mutant("fastpath-reads-do-not-consume", "protocol", "emulator/spi/fastpath.py",
           "                consumed = True\n                last_consuming = i",
           "                last_consuming = i",
           ("emulator/tests/test_spi_model.py::test_vectorized_path_matches_the_transfer_level_path",
            "emulator/tests/test_spi_model.py::test_bus_word_path_matches_transfer_level_for_multi_sensor_frames"),
           "a read never consumes its word: a second read returns the code again instead of an error word"),
    Mutant("fastpath-adc-busy-at-5-ticks", "protocol", "emulator/spi/fastpath.py",
           "busy = tick - last_sampling_tick < CONVERSION_TICKS", "busy = tick - last_sampling_tick <= CONVERSION_TICKS",
           ("emulator/tests/test_spi_model.py::test_vectorized_path_matches_the_transfer_level_path",),
           "a command exactly one conversion time after the last finds the ADC still busy"),
    Mutant("rig-stop-command-at-window-start", "sliding", "bench/rigs/texture_rig.py",
           "t_stop = (sampler.next_slot + to_stop * run.frame) / sampler.slot_rate_Hz",
           "t_stop = sampler.next_slot / sampler.slot_rate_Hz",
           (f"{_RIG}::test_force_control_at_the_lightest_movement",),
           "the stepper's stop is commanded at the snapshot instead of after the frame that reached the target"),
    Mutant("rig-final-read-misses-stop-frames", "sliding", "bench/rigs/texture_rig.py",
           "rest += to_stop  #", "rest += 0  #",
           ("bench/tests/test_texture_rig_reading.py::test_a_trial_does_not_depend_on_how_it_is_read_ahead",),
           "after going back to the snapshot the trial's recording loses the frames through the stop"),
    Mutant("patch-radii-mixed", "sliding", "emulator/sliding.py",
           "for row, (k, m) in zip(full, rows):", "for row, (k, m) in zip(full[::-1], rows):",
           (f"{_SLIDE}::test_spatial_tables_are_the_line_load_convolutions_and_ridge_sums_of_the_surface",),
           "patch radii sharing an FFT length get each other's patch averages"),
    Mutant("pairs-ignore-thermal-material", "exploration", "bench/experiments/pairs.py",
           "if ta.material != tb.material:", "if False:",
           (f"{_EXP}::test_similar_pairs_meet_their_definition_and_are_taken_nearest_first",
            f"{_EXP}::test_similar_pair_admissibility_names_what_differs"),
           "validation pairs may differ in thermal feel (D avoided pairs told apart by non-textural cues)"),
    Mutant("pairs-compliance-x3", "exploration", "bench/experiments/pairs.py",
           "COMPLIANCE_RATIO = 1.5", "COMPLIANCE_RATIO = 4.5",
           (f"{_EXP}::test_similar_pairs_meet_their_definition_and_are_taken_nearest_first",),
           "validation pairs that differ in softness are admitted"),
    Mutant("pairs-rigid-1GPa", "exploration", "bench/experiments/pairs.py",
           "RIGID_MODULUS_PA = 10e6", "RIGID_MODULUS_PA = 1e9",
           (f"{_EXP}::test_similar_pairs_meet_their_definition_and_are_taken_nearest_first",
            f"{_EXP}::test_too_few_similar_pairs_is_an_experiment_error_naming_n_pairs"),
           "only materials stiffer than 1 GPa count as rigid alike"),
    Mutant("pairs-many-per-group", "exploration", "bench/experiments/pairs.py",
           "for one_per_group in (True, False):", "for one_per_group in (False,):",
           (f"{_EXP}::test_similar_pairs_meet_their_definition_and_are_taken_nearest_first",),
           "the validation pairs crowd into one kind of material"),
    Mutant("pairs-linear-rms-height", "exploration", "bench/experiments/pairs.py",
           "math.log10(t.rms_height_m), ", "t.rms_height_m * 1e6, ",
           (f"{_EXP}::test_similar_pairs_meet_their_definition_and_are_taken_nearest_first",),
           "texture similarity measured on RMS height in µm instead of its logarithm"),
    Mutant("newton-slope-without-bristle-damping", "sliding", "emulator/friction.py",
           "slope = k_t * h + c_t + normal * ((sigma0 + sigma1 / h) * dz + mu_v)",
           "slope = k_t * h + c_t + normal * ((sigma0) * dz + mu_v)",
           (f"{_SOLVER}::test_the_residual_slope_is_its_derivative",),
           "Newton's slope of the skin step forgets the bristle damping σ1"),
    Mutant("newton-last-correction-sign", "sliding", "emulator/friction.py",
           "return u_next, znew - dz * du, force - force_slope * du",
           "return u_next, znew - dz * du, force + force_slope * du",
           (f"{_SOLVER}::test_newton_lands_on_a_root_with_that_roots_bristle_and_force",),
           "a step finished to first order corrects its force the wrong way"),
    Mutant("newton-curvature-guard-off", "sliding", "emulator/friction.py",
           "2.0 * abs(slope - slope_last) / abs(u - u_last) * du * du < tol * slope",
           "0.0 * abs(slope - slope_last) / abs(u - u_last) * du * du < tol * slope",
           (f"{_SOLVER}::test_newton_lands_on_a_root_with_that_roots_bristle_and_force",),
           "Newton accepts a step before it has converged"),
    Mutant("newton-keeps-weakening-roots", "sliding", "emulator/friction.py",
           "if not slope > 0.5 * skin_slope:", "if not slope > 0.0:",
           (f"{_SOLVER}::test_where_the_friction_weakens_with_slip_the_step_keeps_the_bracketed_solvers_root",),
           "where friction weakens with slip, Newton keeps the nearest of several roots (lift-off changes)"),
    Mutant("segments-before-first-command", "sliding", "emulator/sliding.py",
           "k = max(lo - 1, 0)", "k = lo - 1",
           (f"{_SOLVER}::test_the_compiled_segment_evaluation_is_the_plain_formula_to_the_bit",),
           "instants before the first motion command read the last segment"),
    Mutant("random-track-unscaled", "sliding", "emulator/texture.py",
           "return track / float(np.sqrt(np.mean(track**2))) * rms", "return track * rms",
           ("emulator/tests/test_texture_tracks.py",),
           "a texture's random relief is not scaled to its RMS height"),
    Mutant("fluctuation-band-variance-halved", "sliding", "emulator/texture.py",
           "return track * (rms * n / math.sqrt(2.0 * band_power))", "return track * (rms * n / math.sqrt(band_power))",
           ("emulator/tests/test_friction_fluctuation.py::"
            "test_fluctuation_rms_is_the_textures_and_the_same_surface_at_any_resolution",),
           "the friction fluctuation's RMS off by √2 (one-sided band power taken as two-sided)"),
    Mutant("rig-snapshot-generator-state-dropped", "sliding", "bench/rigs/texture_rig.py",
           "    bits.state = g.bit_generator.state\n", "\n",
           ("bench/tests/test_texture_rig_reading.py::test_a_trial_does_not_depend_on_how_it_is_read_ahead",),
           "a rewound rig trial draws fresh noise instead of the noise it had"),
    Mutant("filters-columns-reassociated", "filters", "emulator/filters.py",
           "z[0, j] = z[1, j] + xi * b1 - yi * a1", "z[0, j] = z[1, j] + (xi * b1 - yi * a1)",
           (f"{_FILTERS}::test_columns_filtered_along_axis_0_are_lfilters_to_the_bit",),
           "the compiled column filter sums in another order than lfilter (electrode codes' last bits)"),
    Mutant("filters-remembered-zi-not-copied", "filters", "emulator/filters.py",
           "return _sosfilt_zi(sos.shape, sos.tobytes()).copy()", "return _sosfilt_zi(sos.shape, sos.tobytes())",
           (f"{_FILTERS}::test_remembered_steady_state_is_scipys_and_a_fresh_array",),
           "every sensor shares one remembered filter state array (a caller's edit corrupts later sensors)"),
    Mutant("electrodes-shear-run-offset", "electrodes", "emulator/electrodes.py",
           "for x in self._shifted_shapes(s_mm[starts]))", "for x in self._shifted_shapes(s_mm[np.maximum(starts - 1, 0)]))",
           ("emulator/tests/test_electrode_locality.py::test_a_held_shear_computes_one_row_per_run_with_the_same_bits",),
           "each run of equal shear takes the previous run's shear"),
    Mutant("electrodes-compiled-gap-order", "electrodes", "emulator/electrodes.py",
           "g = rest_mm[j] - depth * frac[i, j]\n            g = g - rest_mm[j] * lost[i]\n            g = g + bulge[i, j]",
           "g = rest_mm[j] + bulge[i, j]\n            g = g - rest_mm[j] * lost[i]\n            g = g - depth * frac[i, j]",
           ("emulator/tests/test_electrode_locality.py::test_compiled_gaps_and_volts_are_the_numpy_laws_to_the_bit",),
           "the compiled electrode gaps add the bulge before the dent (voltages' last bits differ from the law)"),
    Mutant("ridge-slopes-no-reset", "sliding", "emulator/sliding.py",
           "        ridged[:] = 0.0", "        pass",
           ("emulator/tests/test_sliding.py::test_spatial_tables_are_the_line_load_convolutions_and_ridge_sums_of_the_surface",),
           "the ridges' slope sum of one patch radius leaks into the next"),
    Mutant("ridge-gain-inverted", "sliding", "emulator/sliding.py",
           "            row[i] = s + gain * (ridged[i] - s)", "            row[i] = ridged[i] + gain * (s - ridged[i])",
           ("emulator/tests/test_sliding.py::test_spatial_tables_are_the_line_load_convolutions_and_ridge_sums_of_the_surface",),
           "the blend of patch slope and ridge sum inverted (ridge gain 1 means a smooth skin)"),
    Mutant("track-slice-boundary", "sliding", "emulator/sliding.py",
           "    if i0 + n + 2 * pad <= n_surface:", "    if i0 + n + 2 * pad <= n_surface + 1:",
           ("emulator/tests/test_sliding.py::test_spatial_tables_are_the_line_load_convolutions_and_ridge_sums_of_the_surface",),
           "a trial's stretch that just wraps past the 1 m surface is sliced as if it did not"),
    Mutant("grid-relief-sin-sign", "sliding", "emulator/texture.py",
           "cos_table[:, :n] - (amplitudes * np.sin(phase))", "cos_table[:, :n] + (amplitudes * np.sin(phase))",
           ("emulator/tests/test_texture_tracks.py::test_the_periodic_relief_on_a_grid_is_the_sum_of_its_cosines",),
           "the periodic relief by angle addition with the wrong sign: the relief at the wrong phase"),
    Mutant("grid-relief-harmonic-shift", "sliding", "emulator/texture.py",
           "        for j, rel in enumerate((1.0, *c.harmonics), start=1):",
           "        for j, rel in enumerate((1.0, *c.harmonics), start=2):",
           ("emulator/tests/test_texture_tracks.py::"
            "test_a_periodic_component_is_its_fundamental_plus_its_harmonics_at_their_orders",),
           "every periodic component's harmonics one order too high"),
    Mutant("window-convolution-centre", "sliding", "bench/textures/properties.py",
           "    left, right = h.size - 1 - (h.size - 1) // 2, (h.size - 1) // 2",
           "    left, right = (h.size - 1) // 2, h.size - 1 - (h.size - 1) // 2",
           ("bench/tests/test_texture_properties.py::test_band_powers_are_the_mean_squares_of_the_whole_record_filtered",),
           "the roughness band-pass inside the windows centred one sample off (even filters)"),
    Mutant("fir-taps-shared", "sliding", "bench/textures/properties.py",
           "    return _fir_taps(fs_hz, order, tuple(band_hz)).copy()", "    return _fir_taps(fs_hz, order, tuple(band_hz))",
           ("bench/tests/test_texture_properties.py::test_filter_is_designed_once_and_handed_out_as_a_copy",),
           "every caller gets the one remembered FIR array (an edit corrupts every later trial's roughness)"),
    Mutant("thermal-held-rows-shifted", "thermal", "emulator/thermal.py",
           "rows = slice(k - k_held, k - k_held + run_end - j)",
           "rows = slice(k - k_held + 1, k - k_held + run_end - j + 1)",
           (f"{_LIVE}::test_codes_do_not_depend_on_block_size_or_on_how_reads_are_cut",),
           "a held chunk's closed-form states read one step off"),
    Mutant("thermal-runs-cross-chunks", "thermal", "emulator/thermal.py",
           "        chunk_starts = (k0 + np.arange(times.size)) % CHUNK_STEPS == 0",
           "        chunk_starts = np.arange(times.size) % CHUNK_STEPS == 0",
           (f"{_LIVE}::test_codes_do_not_depend_on_block_size_or_on_how_reads_are_cut",),
           "the live network's runs no longer break at absolute chunk starts (self-heating updated late)"),
    Mutant("thermal-runs-ignore-area", "thermal", "emulator/thermal.py",
           "(area[1:] != area[:-1])", "False",
           (f"{_LIVE}::test_the_commanded_finger_cools_the_fingertip_in_the_order_of_the_surfaces_effusivity",
            f"{_LIVE}::test_codes_do_not_depend_on_block_size_or_on_how_reads_are_cut"),
           "a changed contact patch area keeps the old step response"),
    Mutant("thermal-touches-last-wins", "thermal", "emulator/thermal.py",
           "first = on & (index < 0)", "first = on",
           (f"{_LIVE}::test_the_touches_of_many_steps_at_once_are_the_first_touching_contact_instant_by_instant",),
           "of overlapping contacts the last wins instead of the first"),
    Mutant("thermal-step-key-ignores-live", "thermal", "emulator/thermal.py",
           "(contact[0].name, contact[1]), dt, live)", "(contact[0].name, contact[1]), dt)",
           (f"{_LIVE}::test_a_steps_contiguous_response_is_the_discretization_remembered",),
           "a planned contact gets the live contact's discretization from the shared cache"),
    Mutant("engine-group-results-shifted", "campaigns", "bench/campaigns/engine.py",
           "first = {f.key: i * size for i, f in enumerate(futures)}",
           "first = {f.key: min(i * size + 1, len(tasks) - 1) for i, f in enumerate(futures)}",
           ("bench/tests/test_campaign_engine.py::test_grouped_tasks_give_the_same_results_in_task_order_and_name_a_failing_task_by_its_own_index",),
           "a group's results stored one place off (results out of task order)"),
    Mutant("engine-failure-names-the-group", "campaigns", "bench/campaigns/engine.py",
           "raise TaskFailed(first + k, f", "raise TaskFailed(first, f",
           ("bench/tests/test_campaign_engine.py::test_grouped_tasks_give_the_same_results_in_task_order_and_name_a_failing_task_by_its_own_index",),
           "a failing task in a group is reported as the group's first task"),
    Mutant("explicit-pairs-may-overlap", "exploration", "bench/experiments/experiment.py",
           "if twice and not same:", "if False:",
           (f"{_EXP}::test_bad_experiment_files_name_field_and_value",),
           "an experiment file may list one texture in two validation pairs"),
    Mutant("confused-pairs-silent-shortfall", "exploration", "bench/experiments/experiment.py",
           "            return pairs\n    raise ExperimentError(", "            return pairs\n    return pairs\n    raise ExperimentError(",
           (f"{_EXP}::test_too_few_pairs_by_confusion_or_chance_is_an_experiment_error_too",),
           "random-within-group and most-confused hand back fewer pairs than asked, silently"),
    Mutant("double-noise-misses-spi-coupling", "exploration", "bench/experiments/trials.py",
           '"mains_amplitude_V", "spi_coupling_rms_V", "tdc_noise_V")', '"mains_amplitude_V", "tdc_noise_V")',
           (f"{_EXP}::test_the_double_noise_ablation_doubles_every_noise_source",),
           "the double-noise ablation leaves the SPI coupling noise as it was"),
    Mutant("double-noise-current-through-r-x8", "exploration", "bench/experiments/trials.py",
           'scaled["amp_current_noise_A_per_rtHz"] /= noise_scale ** 2', "pass",
           (f"{_EXP}::test_the_double_noise_ablation_doubles_every_noise_source",),
           "the double-noise ablation scales the amplifier's current noise ×2 on top of R ×4 (×8 through R)"),
    Mutant("hum-phase-from-unreduced-index", "noise", "emulator/extrinsic.py",
           "((f * n) % fs)", "(f * n)",
           ("emulator/tests/test_fast_paths.py::test_the_tabulated_hum_is_the_per_sample_formula_bit_for_bit",),
           "the hum's phase from the raw sample index (its rounding grows with time)"),
    Mutant("hum-table-restarts-each-block", "noise", "emulator/extrinsic.py",
           "start = block.n0 % table.size", "start = 0",
           ("emulator/tests/test_stability.py::test_every_grid_signal_is_the_same_to_the_bit_whatever_the_block_size",),
           "every block starts the mains hum at phase 0: results depend on block size"),
    Mutant("channel-plan-reused-by-shape", "adc", "emulator/sensor.py",
           "last[0].shape == channels.shape and np.array_equal(last[0], channels)",
           "last[0].shape == channels.shape",
           ("emulator/tests/test_model.py::test_each_batch_is_read_by_its_own_channels_whatever_the_batch_before",),
           "a batch is read with the previous batch's channel plan when only their lengths agree"),
    Mutant("force-curve-shortcut-too-early", "skin", "emulator/mechanics.py",
           "x.max() <= 30", "x.max() <= 300",
           ("emulator/tests/test_fast_paths.py::test_the_force_curve_of_a_block_that_presses_throughout_is_the_masked_formulas",),
           "the force curve's log(1 + eˣ) shortcut taken where eˣ overflows"),
    Mutant("compiled-lfilter-reassociated", "filters", "emulator/filters.py",
           "z0 = z1 + xi * b1 - yi * a1", "z0 = xi * b1 - yi * a1 + z1",
           ("emulator/tests/test_fast_paths.py::test_lfilter_compiled_or_without_the_wrapper_gives_scipys_numbers",),
           "the compiled filter section adds in another order than lfilter (other bits)"),
    Mutant("cli-blas-threads-unlimited", "host", "bench/cli/__init__.py",
           '    os.environ.setdefault(_variable, "1")', "    pass",
           (f"{_CLI}::test_the_command_runs_blas_on_one_thread_unless_the_user_chose",),
           "the command lets BLAS spin a thread per core around the emulator's tiny matrix products"),
]

# --- issue 10: skin mechanics, local electrodes, units, the BioTac SP, several fingers -------------------------------
_SKIN = "emulator/tests/test_skin_mechanics.py"
_LOC = "emulator/tests/test_electrode_locality.py"
_SP = "emulator/tests/test_variant_sp.py"
_SP_HOST = "firmware_tests/tests/test_variant_sp.py"
_UNITS = "bench/tests/test_units.py"
_FINGERS = "bench/tests/test_multi_finger.py"
CATALOGUE += [
    Mutant("displacement-gain-fixed", "skin", "emulator/mechanics.py",
           "self.gain = skin_fluid(params).pressure_per_displacement_Pa_per_m", "self.gain = 3.17e6",
           (f"{_SKIN}::test_displacement_gain_is_the_displaced_liquid_over_the_loaded_area",),
           "the piezo path's gain a fixed number instead of the liquid displaced over the loaded area"),
    Mutant("pac-noise-every-channel", "noise", "emulator/adc.py",
           "if channels.size and channels[p] == PAC:", "if channels.size and channels[p] >= 0:",
           ("emulator/tests/test_channel_noise.py::"
            "test_pac_path_noise_lands_on_pac_conversions_only_and_leaves_the_others_unchanged",),
           "the PAC path's extra noise on every channel (quiet channels at 1.15 LSB again)"),
    Mutant("hum-no-3rd-harmonic", "noise", "emulator/extrinsic.py",
           "(3, 3 * f, a * params.mains_harmonic3_ratio)", "(3, 3 * f, 0.0 * a * params.mains_harmonic3_ratio)",
           ("emulator/tests/test_channel_noise.py::test_hum_has_its_fundamental_and_2nd_and_3rd_harmonics_at_their_amplitudes",),
           "mains hum without its 3rd harmonic"),
    Mutant("skin-elastic-no-creep", "skin", "emulator/params.py",
           "skin_relaxed_modulus_fraction: float = _p(\n        0.6,",
           "skin_relaxed_modulus_fraction: float = _p(\n        1.0,",
           (f"{_SKIN}::test_held_force_creeps_up_and_unloading_lags_loading",),
           "a purely elastic skin: no creep under a held force, no loading/unloading loop"),
    Mutant("inflation-exponent-3", "skin", "emulator/params.py",
           "resting_pressure_exponent: float = _p(\n        1.5,", "resting_pressure_exponent: float = _p(\n        3.0,",
           (f"{_SKIN}::test_force_slope_follows_geometry_and_inflation_not_the_pdc_scale",
            f"{_SKIN}::test_resonance_is_sqrt_k_over_m_and_anchored_at_nominal_inflation"),
           "the skin stiffens with the cube of inflation: fluid stiffness, force slope and resonance all move"),
    Mutant("electrode-bulge-4x-wider", "electrodes", "emulator/params.py",
           "bulge_width_ratio: float = _p(\n        0.7071,", "bulge_width_ratio: float = _p(\n        2.8284,",
           (f"{_LOC}::test_a_1N_press_changes_mostly_the_nearest_electrodes_and_little_beyond_10_mm",),
           "the displaced liquid bulges over a ring four times wider: far electrodes move, locality is lost"),
    Mutant("electrode-dent-no-creep", "electrodes", "emulator/electrodes.py",
           "Creep.standard_linear_solid(sf.creep_time_s, sf.creep_ratio)",
           "Creep.standard_linear_solid(sf.creep_time_s, 1.0)",
           (f"{_LOC}::test_a_held_force_makes_the_electrode_code_creep_and_a_release_recovers",),
           "the electrode dent does not creep with the skin"),
    Mutant("electrode-gap-spread-ignored", "electrodes", "emulator/electrodes.py",
           "g + p.electrode_gap_spread_mm * z", "g + 0.0 * z",
           (f"{_LOC}::test_resting_gaps_are_nominal_without_spread_and_drawn_per_electrode_with_it",
            f"{_LOC}::test_a_units_resting_codes_differ_by_electrode_and_every_rest_uses_them"),
           "every electrode of every unit rests at the same gap"),
    Mutant("unit-seed-ignored", "units", "emulator/units.py",
           "draw_params(int(which), base)", "draw_params(0, base)",
           (f"{_UNITS}::test_a_unit_seed_reproduces_the_unit_bit_for_bit_and_units_differ",),
           "every unit seed draws the same unit"),
    Mutant("sensor-2-stimuli-to-sensor-1", "fingers", "bench/scenes/scene.py",
           "per_sensor.setdefault(k, []).append(s)", "per_sensor.setdefault(1, []).append(s)",
           (f"{_FINGERS}::test_stimuli_of_sensor_2_do_not_reach_sensor_1",),
           "a stimulus addressed to finger k reaches finger 1"),
    Mutant("hosts-see-finger-1-everywhere", "fingers", "bench/hosts/scene_sensors.py",
           "base.for_sensor(k), sequence", "base.for_sensor(1), sequence",
           (f"{_FINGERS}::test_the_bridge_firmware_and_driver_see_each_fingers_own_touch",),
           "behind the bridge every finger is built as finger 1"),
    Mutant("sp-23-electrodes", "variant", "emulator/channels.py",
           '"biotac-sp": 24}', '"biotac-sp": 23}',
           (f"{_SP}::test_sp_channel_map_and_commands",), "the BioTac SP loses E24"),
    Mutant("model-19-electrode-recognises-e20", "variant", "emulator/spi/model.py",
           "self.recognized = self.variant.sampled_channels",
           "self.recognized = ch.variant('biotac-sp').sampled_channels",
           (f"{_SP}::test_a_19_electrode_sensor_answers_e20_to_e24_with_clear_error_words",),
           "a 19-electrode sensor answers E20..E24 as if it had them"),
    Mutant("fastpath-default-tables-for-sp", "variant", "emulator/spi/fastpath.py",
           "_tables(ch.variant(name).sampled_channels)", "_tables(ch.SAMPLED_CHANNELS)",
           (f"{_SP}::test_a_biotac_sp_answers_all_24_electrodes_with_data",),
           "the vectorized SPI path decodes every variant as the 19-electrode sensor"),
    Mutant("rtl-sp-lacks-e24", "variant", "emulator/rtl/biotac_spi.v",
           "6'd40 : 6'd35", "6'd39 : 6'd35",
           (f"{_SP}::test_rtl_54_slot_frame_and_e20_to_e24_match_the_software_model",),
           "the RTL's SP does not recognise E24"),
    Mutant("firmware-sp-44-slot-frame", "variant", "firmware_tests/firmware/bt_bridge.c",
           "b->pattern_len = sizeof SP_FRAME;", "b->pattern_len = 44;",
           (f"{_SP_HOST}::test_an_sp_streams_the_54_slot_frame_with_data_in_every_slot",),
           "the bridge firmware streams only 44 slots of an SP's frame"),
    Mutant("firmware-sp-frame-e20-e21-swapped", "variant", "firmware_tests/firmware/bt_bridge.c",
           "36, 0, 37, 0, 38, 0,", "37, 0, 36, 0, 38, 0,",
           (f"{_SP_HOST}::test_an_sp_streams_the_54_slot_frame_with_data_in_every_slot",),
           "the firmware's SP frame samples E21 where E20 belongs"),
    Mutant("client-e20-even-parity", "variant", "firmware_tests/cheetah_client/biotac_client.c",
           "0xC7, 0x80, 0xC8, 0x80", "0xC7, 0x80, 0xC9, 0x80",
           (f"{_SP_HOST}::test_a_vendor_style_cheetah_client_gets_sp_data_and_clear_errors_from_a_19_electrode_sensor",),
           "the vendor-style client sends E20's command with even parity"),
    Mutant("driver-error-words-as-data", "variant", "bench/hosts/driver.py",
           "return self.status == 0", "return self.status != 1",
           (f"{_SP_HOST}::test_vendor_e20_to_e24_on_a_19_electrode_sensor_are_errors_never_data",),
           "the driver hands error words (status 2) out as data"),
    # the texture library against its sources, the rig's geometry against D's 75 mm squares
    Mutant("window-ignores-lead-tail", "texture", "bench/textures/properties.py",
           "return rec.slide_start_s + lead * d, rec.slide_end_s - tail * d",
           "return rec.slide_start_s + MEASURE_LEAD * d, rec.slide_end_s - MEASURE_TAIL * d",
           ("bench/tests/test_library_sources.py::test_roughness_sigma_falls_about_as_one_over_root_window",),
           "the measurement window's arguments are silently ignored"),
    Mutant("rig-stroke-10cm", "texture", "bench/rigs/texture_rig.py",
           "distance_m: float = 0.05", "distance_m: float = 0.1",
           ("bench/tests/test_library_sources.py::test_stroke_and_contact_patch_fit_on_ds_texture_squares",),
           "the stroke no longer fits D's 75 mm texture squares"),
    Mutant("library-ripstop-mu-off-class", "texture", "fixtures/textures/library.toml",
           'mu_static = 0.45\nmu_kinetic = 0.383\nmodulus_MPa = 1.0\nmaterial = "cotton fabric"\nseed = 86',
           'mu_static = 0.5\nmu_kinetic = 0.383\nmodulus_MPa = 1.0\nmaterial = "cotton fabric"\nseed = 86',
           ("bench/tests/test_library_sources.py::test_every_texture_friction_follows_its_cited_class",),
           "one texture's friction moved off its cited class without a source"),
    # the rig's geometry: D's 75 mm squares
    Mutant("rig-start-anywhere-on-1m", "texture", "bench/rigs/texture_rig.py",
           'uniform(first, last))', 'uniform(0.0, 1.0))',
           (f"{_RIG}::test_every_trial_of_a_texture_runs_on_its_one_75_mm_square",
            "bench/tests/test_trial_spread.py::test_on_ds_square_overlapping_strokes_scatter_less_but_more_than_the_sensor_noise"),
           "trials start anywhere on the 1 m surface, each on its own piece of material, not on the texture's square"),
    # compiled host path, thermal runs, snapshot and log (speed work: each pinned by a consistency test)
    Mutant("thermal-step-table-ignores-area", "thermal", "emulator/thermal.py",
           "keys = [None if c is None else (c[0].name, c[1], c[2]) for c in contacts]",
           "keys = [None if c is None else (c[0].name, c[2]) for c in contacts]",
           (f"{_LIVE}::test_the_commanded_finger_cools_the_fingertip_in_the_order_of_the_surfaces_effusivity",
            f"{_LIVE}::test_the_compiled_runs_are_numpys_steps_run_by_run"),
           "a grown contact patch keeps the first patch's step response"),
    Mutant("thermal-arrival-not-reset", "thermal", "emulator/thermal.py",
           "            x[4:] = temperature[i]", "            x[4:] = x[4:]",
           (f"{_LIVE}::test_the_compiled_runs_are_numpys_steps_run_by_run",),
           "a newly touched object does not arrive at its own temperature (no physics test sees it: detached layers "
           "already relax to ambient, the rig object's temperature)"),
    Mutant("rig-clone-c-order", "texture", "bench/rigs/texture_rig.py",
           'y = memo[i] = x.copy(order="K")', "y = memo[i] = x.copy()",
           ("bench/tests/test_rig_snapshot.py::test_the_snapshot_copier_gives_deepcopys_copy",),
           "the rewind snapshot changes arrays' memory order"),
    Mutant("rig-log-filter", "texture", "bench/rigs/texture_rig.py",
           "at = s.channels == channel", "at = s.channels >= channel",
           ("bench/tests/test_rig_log.py::test_pac_and_pdc_kept_as_read_are_all_samples_read_filtered",),
           "the rig log's PAC/PDC pick up other channels' samples"),
    Mutant("sensor-interp-reassociated", "chain", "emulator/sensor.py",
           "out[p] = h[k[p]] * (1.0 - frac[p]) + h[k[p] + 1] * frac[p]",
           "out[p] = h[k[p]] + (h[k[p] + 1] - h[k[p]]) * frac[p]",
           ("emulator/tests/test_model.py::test_the_compiled_interpolation_is_the_numpy_formula_to_the_bit",),
           "the sampling interpolation off in the last bits"),
    Mutant("sampler-read-delay-from-command", "protocol", "bench/running/sampler.py",
           "t_cmd, t + sample_delay_s", "t_cmd, t_cmd + sample_delay_s",
           ("emulator/tests/test_spi_model.py::test_the_samplers_transfers_are_its_slots_command_then_read",),
           "the sampler's reads come 3.75 µs early (timed from the command's start)"),
    # how sliding vibration scales with the normal force (bench/tests/test_force_scaling.py)
    Mutant("slope-force-load-independent", "sliding", "emulator/friction.py",
           "out_tangential[n] = f_sum / substeps + normal * slope", "out_tangential[n] = f_sum / substeps + slope",
           ("bench/tests/test_force_scaling.py::test_the_tangential_path_power_grows_about_as_force_squared",),
           "the ridges' slope force no longer scales with the normal load: tangential vibration stops growing ~N²"),
    Mutant("patch-kernel-one-sample", "sliding", "emulator/sliding.py",
           "m = max(1, int(np.floor(a / dx_m)))", "m = 1",
           ("bench/tests/test_force_scaling.py::test_the_normal_path_power_falls_with_force",),
           "no patch averaging: the normal path's vibration power grows with force instead of falling"),
    Mutant("patch-radius-fixed-at-1N", "sliding", "emulator/friction.py",
           "r = radius_1N * cbrt_n  # the patch radius", "r = radius_1N  # the patch radius",
           ("bench/tests/test_force_scaling.py::test_the_normal_path_power_falls_with_force",),
           "the contact patch does not grow with load (foam's normal path then rises with force)"),
    # the user review's fixes (2026-11-22): each documented behaviour has a test that catches its removal
    Mutant("stimulus-past-the-end-accepted", "scenes", "bench/scenes/scene.py",
           "if duration is not None and s.end_s > duration + END_TOLERANCE_S:",
           "if duration is not None and s.start_s > duration + END_TOLERANCE_S:",
           ("bench/tests/test_scene.py::test_a_stimulus_ending_after_the_scene_is_refused_as_a_slide_is",),
           "a press, vibration or sweep that runs past the scene's end is accepted and silently cut off"),
    Mutant("first-signal-stops-the-exports", "outputs", "bench/running/signals.py",
           "signum = self._writing_signum if self._writing else self.signum",
           "signum = self.signum",
           ("bench/tests/test_run_review.py::test_one_signal_mid_simulation_in_process_writes_everything",),
           "one Ctrl-C mid-simulation also skips codes.npz, samples.csv and the plots"),
    Mutant("trial-seed-by-list-position", "experiments", "bench/experiments/trials.py",
           "trial_seed(seed, stage, tex, m_id, k)", "trial_seed(seed, stage, tex, movements.index(m), k)",
           ("bench/tests/test_sweep_review.py::test_a_trials_seed_depends_on_its_grid_movement_not_on_its_place_in_the_list",),
           "a trial's seed follows where its movement sits in the list, so a selection changes its result"),
    Mutant("pilot-trend-sign-flipped", "experiments", "bench/verification/claims/exploration.py",
           '"force": rho(u[:, p], force), "velocity"', '"force": -rho(u[:, p], force), "velocity"',
           ("bench/tests/test_pilot_trends.py",),
           "the pilot-trend claims read U's trend against force with the wrong sign (a deviation would pass)"),
    # the second review's fixes (2026-11-22)
    Mutant("force-removes-before-checking", "outputs", "bench/reporting/outdir.py",
           "        if foreign:\n            raise OutDirError(", "        if False:\n            raise OutDirError(",
           ("bench/tests/test_run_review2.py::test_force_refuses_a_foreign_file_in_a_later_sensor_folder_and_removes_nothing",),
           "run --force removes an earlier run's files although the folder holds someone else's"),
    Mutant("second-signal-before-the-chunk-ignored", "outputs", "bench/running/signals.py",
           "if self._writing_signum is None and (self._writing or self.signum is not None):",
           "if self._writing_signum is None and self._writing:",
           ("bench/tests/test_run_review2.py::test_two_signals_before_the_chunk_ends_stop_the_exports_and_plots",),
           "a second Ctrl-C before the current chunk ends no longer stops the exports and plots"),
    Mutant("record-force-deletes-any-csv", "host", "bench/cli/hosts.py",
           "return head is not None and head.splitlines()[:1] == [RECORDING_CSV_HEADER.encode()]", "return True",
           ("bench/tests/test_run_review2.py::test_record_force_refuses_a_csv_beside_out_that_is_not_a_recording",),
           "record --force deletes a user's own .csv beside --out"),
    Mutant("sweep-writes-without-holding-signals", "experiments", "bench/cli/experiments.py",
           "with signals_held():  # a signal meanwhile: every file finished first, then the stop",
           "if True:  # a signal meanwhile: every file finished first, then the stop",
           ("bench/tests/test_sweep_review2.py::test_a_signal_while_the_sweep_writes_finishes_every_file_first",),
           "a Ctrl-C while a sweep writes its files leaves some unwritten"),
    Mutant("atomic-write-keeps-its-temporary", "outputs", "bench/atomic.py",
           "        with contextlib.suppress(OSError):\n            os.unlink(tmp)\n        raise",
           "        raise",
           ("bench/tests/test_sweep_review2.py::test_atomic_write_removes_its_temporary_file_on_ctrl_c",),
           "an interrupted atomic write leaves its temporary file behind"),
    # the third review and the issue audit (2026-11-22, evening)
    Mutant("texture-frozen-under-skin", "sliding", "emulator/friction.py",
           "            p += vr * h\n", "            p += 0.0 * h\n",
           ("bench/tests/test_claims.py::test_published_figures_hold[sliding]",),
           "the texture does not pass under the slipping skin (no sliding vibration: the slip row falls)"),
    Mutant("skin-spring-forgets-deflection", "sliding", "emulator/friction.py",
           "    return k_t * (x + u * h) + c_t * u - force, slope, znew, force",
           "    return k_t * (u * h) + c_t * u - force, slope, znew, force",
           ("bench/tests/test_claim_rows_issue8.py::test_slip_onset_rows_fail_when_the_stick_is_as_loud_as_the_slip",
            "bench/tests/test_claims.py::test_published_figures_hold[sliding]"),
           "the skin's tangential spring forgets its deflection (no stick phase, no ramp)"),
    Mutant("grating-even-harmonics", "sliding", "fixtures/textures/library.toml",
           "amplitude_um = 318.0\nharmonics = [0.0, -0.333, 0.0, 0.2, 0.0, -0.143]",
           "amplitude_um = 318.0\nharmonics = [0.5, -0.333, 0.25, 0.2, 0.167, -0.143]",
           ("bench/tests/test_claims.py::test_published_figures_hold[sliding]",),
           "the 3 mm grating gains even harmonics (its documented harmonics deviation would pass)"),
    Mutant("friction-fluctuation-1-over-q3", "sliding", "emulator/texture.py",
           "amplitude = 1.0 / np.sqrt(k)  # power ∝ 1/q", "amplitude = 1.0 / k ** 1.5  # power ∝ 1/q",
           ("bench/tests/test_claims.py::test_published_figures_hold[texture-properties]",),
           "the friction fluctuation's spectrum 1/q³ instead of 1/q (the centroid deviations would pass)"),
    Mutant("skin-replace-keeps-worn-ridges", "sliding", "emulator/skin.py",
           "ridge_height_m=self.ridge_height_new_m, serial=self.serial + 1",
           "ridge_height_m=self.ridge_height_m, serial=self.serial + 1",
           ("bench/tests/test_claim_rows_issue8.py::test_a_replacement_that_keeps_the_worn_ridges_fails_the_restored_spread_row",),
           "a replaced skin keeps the worn ridges (repeatability is not restored)"),
    Mutant("electrodes-feel-no-shear", "electrodes", "emulator/sliding.py",
           "normal[found], tangential[found] = self._normal[0][at[found]], self._tangential[0][at[found]]",
           "normal[found], tangential[found] = self._normal[0][at[found]], 0.0 * self._tangential[0][at[found]]",
           ("emulator/tests/test_electrode_shear.py::test_the_pattern_shifts_at_slip_along_the_shear_and_follows_the_friction_force",),
           "the electrodes do not feel the friction model's tangential force"),
    Mutant("rig-decides-every-frame", "rig", "bench/rigs/texture_rig.py",
           "    batch_s: float = 0.1", "    batch_s: float = 0.01",
           (f"{_RIG}",), "the rig's controller acts on every 10 ms frame instead of D's 100 ms batches"),
    Mutant("spi-fault-at-bit-0-ignored", "protocol", "emulator/spi/model.py",
           "return (self.miso_flip_bit is not None or self.mosi_flip_bit is not None",
           "return (bool(self.miso_flip_bit) or bool(self.mosi_flip_bit)",
           ("emulator/tests/test_spi_faults_at_zero.py",), "an SPI bit flip at bit 0 counts as no fault"),
    Mutant("bridge-runs-before-the-host-speaks", "host", "bench/hosts/bridge.py",
           "        host_spoke = self.realtime\n", "        host_spoke = True\n",
           ("bench/tests/test_bridge_start.py::test_virtual_time_stands_still_until_the_host_sends_its_first_byte",),
           "unpaced, virtual time runs on before the host sends START (scripted stimuli are lost)"),
    Mutant("baselines-ties-count-as-wins", "experiments", "bench/experiments/experiment.py",
           "(strict and acc == acc_b and moves == moves_b)", "(strict and False)",
           ("bench/tests/test_experiment_report_picks.py",),
           "the strict beats-the-baselines count takes a tie for a win"),
    Mutant("claims-exploration-ignores-its-cluster", "experiments", "bench/verification/claims/exploration.py",
           "cluster=b.cluster or ClusterSpec.from_env()", "cluster=ClusterSpec.from_env()",
           ("bench/tests/test_campaigns_on_dask.py::"
            "test_the_exploration_group_runs_its_experiment_on_the_claims_cluster",),
           "claims --scheduler/--workers do not reach the exploration group's experiment"),
    Mutant("benchmark-effects-variant-dropped", "benchmark", "bench/verification/benchmark.py",
           "seed=1, noise=noise, variant=variant)", "seed=1, noise=noise)",
           ("bench/tests/test_benchmark_effects.py::test_every_row_runs_its_effect_with_and_not_without",),
           "the per-effect table's BioTac SP row streams the 19-electrode sensor"),
    Mutant("ridge-crest-held-at-its-base", "sliding", "emulator/friction.py",
           "x = base - deflection / dx  # the crest's position", "x = base  # the crest's position",
           ("emulator/tests/test_ridge_release.py::test_caught_crests_add_friction_as_prandtl_tomlinson_predicts",),
           "the resolved ridges read their limit under the base, not where the held crest is: no snaps"),
    Mutant("reference-ridges-effective", "sliding", "emulator/fidelity.py",
           'ridges="resolved"', 'ridges="effective"',
           ("emulator/tests/test_ridge_release.py::"
            "test_the_profiles_ridge_models_and_the_effective_path_is_the_comb_alone",),
           "the reference profile treats the ridges as a rigid comb (no release events)"),
    Mutant("ridge-slip-floor-1-um-per-s", "sliding", "emulator/friction.py",
           "RIDGE_SLIP_FLOOR_M_PER_S = CATCH_VELOCITY_M_PER_S", "RIDGE_SLIP_FLOOR_M_PER_S = 1e-6",
           ("emulator/tests/test_ridge_release.py::test_ridges_release_nothing_while_the_skin_sticks",),
           "the stuck skin's micro-slip moves the resolved ridges' crests: they push it forward before it slips"),
    Mutant("ring-retry-keeps-the-ridges-loaded", "sliding", "emulator/sliding.py",
           '                c["ridge_parts"][-1][:] = ridge_state', "                pass",
           ("emulator/tests/test_ridge_release.py::"
            "test_a_ring_piece_run_again_starts_from_the_ridges_state_it_started_from",),
           "a long slide's piece run again starts from the ridges' state at its end (loaded twice)"),
    Mutant("ridge-share-on-top-of-mu", "sliding", "emulator/friction.py",
           "ridge_mean = math.copysign(mu_ridges * normal, vr) if moving else 0.0", "ridge_mean = 0.0",
           ("emulator/tests/test_ridge_release.py::test_the_textures_measured_friction_holds_the_ridges_share",),
           "the resolved ridges' dissipation adds to the texture's measured µ, which holds it already"),
    Mutant("ridge-share-forward-only", "sliding", "emulator/friction.py",
           "ridge_mean = math.copysign(mu_ridges * normal, vr) if moving else 0.0",
           "ridge_mean = mu_ridges * normal if moving else 0.0",
           ("emulator/tests/test_ridge_release.py::test_a_reverse_slide_mirrors_the_forward_one",),
           "the ridges' mean share is taken off in the forward direction only"),
    Mutant("ridge-share-off-a-stuck-skin", "sliding", "emulator/friction.py",
           "ridge_mean = math.copysign(mu_ridges * normal, vr) if moving else 0.0",
           "ridge_mean = math.copysign(mu_ridges * normal, vr)",
           ("emulator/tests/test_ridge_release.py::test_the_share_is_taken_only_while_the_ridges_move",),
           "the ridges' mean share is taken off while they do not move (a stuck skin loses force)"),
    Mutant("leak-pressure-held", "faults", "emulator/mechanics.py",
           "        return {\"fluid_pressure_Pa\": self.params.resting_pressure_at(volume)}",
           "        return {\"fluid_pressure_Pa\": np.full(block.n, self.value)}",
           ("emulator/tests/test_fluid_leak.py::test_the_resting_pdc_follows_the_pressure_volume_curve_down",
            "bench/tests/test_campaign_leak.py::test_a_leaking_finger_shows_its_falling_pressure_through_firmware_and_driver"),
           "a leaking finger keeps its resting pressure (PDC does not fall)"),
    Mutant("leak-force-share-kept", "faults", "emulator/mechanics.py",
           "            static = static * self.leak.force_gain(self.params, block.times)", "            pass",
           ("emulator/tests/test_fluid_leak.py::test_a_press_reaches_the_fluid_less_as_the_finger_empties",),
           "a leaking finger's contacts reach the fluid as fully as a filled one's"),
    Mutant("leak-electrodes-unmoved", "faults", "emulator/electrodes.py",
           "        return 1.0 - self.leak.volume_mL(v0, t) / v0", "        return None",
           ("emulator/tests/test_fluid_leak.py::test_the_electrodes_read_gaps_thinned_with_the_fluid_lost",),
           "the fluid gaps over a leaking finger's electrodes do not thin"),
    Mutant("leak-vibration-stiffness-kept", "faults", "emulator/mechanics.py",
           "            pressure = pressure * self.leak.stiffness_gain(self.params, block.times)", "            pass",
           ("emulator/tests/test_fluid_leak.py::test_a_skin_displacement_makes_less_pressure_as_the_finger_empties",),
           "a leaking finger's skin vibration pushes against the full finger's fluid stiffness"),
    Mutant("leak-started-sensor-settles-full", "faults", "emulator/mechanics.py",
           '        return {"fluid_pressure_Pa": self.start_value}', '        return {"fluid_pressure_Pa": self.value}',
           ("emulator/tests/test_fluid_leak.py::test_a_sensor_started_after_the_leak_began_starts_at_the_pressure_left",),
           "a sensor started mid-leak settles at the full finger's pressure (a step and a railed PAC at its start)"),
    Mutant("scene-faults-19-electrodes", "variant", "bench/scenes/scene.py",
           "and 1 <= n <= n_electrodes for n in v):", "and 1 <= n <= 19 for n in v):",
           ("bench/tests/test_scene_sp_faults.py::test_a_biotac_sp_scene_faults_its_extra_electrodes",),
           "a scene of BioTac SPs cannot fault E20..E24 (electrode faults checked against 19 electrodes)"),
    Mutant("finger-faults-to-every-finger", "faults", "bench/scenes/scene.py",
           "skins_k,\n                                dict(faults_of.get(k, common)))",
           "skins_k,\n                                dict(faults_of[1]))",
           ("bench/tests/test_scene_sensor_faults.py::test_each_sensor_has_the_scenes_faults_and_its_own",
            "bench/tests/test_scene_sensor_faults.py::test_the_sensors_built_for_a_host_carry_each_fingers_own_faults"),
           "sensor 1's own faults reach every finger of the scene"),
    Mutant("finger-faults-lost-in-one-sensor-scene", "faults", "bench/scenes/scene.py",
           "trial_skins=list(sp.trial_skins), faults=dict(sp.faults),",
           "trial_skins=list(sp.trial_skins),",
           ("bench/tests/test_scene_sensor_faults.py::test_the_sensors_built_for_a_host_carry_each_fingers_own_faults",),
           "a finger run on its own (run, bridge, Cheetah) has sensor 1's faults, not its own"),
    Mutant("finger-fault-given-twice-accepted", "faults", "bench/scenes/scene.py",
           "    for key in sorted(set(common) & set(own)):", "    for key in sorted(set(common) & set()):",
           ("bench/tests/test_scene_sensor_faults.py::test_a_sensors_own_faults_are_checked_by_name",),
           "a fault given in [faults] and in a sensor's own table is silently taken from the sensor's"),
    Mutant("rails-count-only-the-top", "reporting", "bench/running/aggregate.py",
           '"rail_samples": int(hist[0] + hist[-1]),', '"rail_samples": int(hist[-1]),',
           ("bench/tests/test_report_readability.py::test_a_railed_channel_is_counted_and_named",),
           "a channel clipped at the bottom rail is reported as unclipped"),
    Mutant("rtl-reset-fires-a-phantom-request", "rtl", "emulator/rtl/biotac_spi.v",
           "    always @(posedge cs_n) begin\n        if (accept_sample) sample_req <= ~sample_req;",
           "    always @(posedge cs_n or negedge rst_n) begin\n        if (!rst_n) sample_req <= 1'b0;\n"
           "        else if (accept_sample) sample_req <= ~sample_req;",
           ("emulator/tests/test_rtl.py::test_cpp_harness_reproduces_every_golden_vector",),
           "a sensor reset after an odd number of conversions asks the bench for a conversion nobody commanded"),
    Mutant("reset-keeps-the-resend-buffer", "spi", "emulator/spi/model.py",
           "        self.last_sent: int | None = None\n        self.last_sampling_tick",
           "        self.last_sent = getattr(self, 'last_sent', None)\n        self.last_sampling_tick",
           ("emulator/tests/test_spi_model.py::test_reset_forgets_the_resend_buffer_too",
            "emulator/tests/test_spi_vectors.py"),
           "a reset sensor resends the word it served before the reset"),
    Mutant("brownout-between-frames-only", "faults", "bench/hosts/cosim.py",
           '                j = max(i, int(np.searchsorted(start, self.resets[0][0], side="left")))',
           '                j = n',
           ("bench/tests/test_campaign_cases.py::test_a_brownout_inside_a_frame_loses_exactly_the_pending_result",),
           "a brown-out scheduled inside a frame never resets the sensor (the campaign's reset case checks nothing)"),
    Mutant("mount-noise-density-over-the-whole-grid", "noise", "emulator/extrinsic.py",
           "np.sqrt(fs / 2.0 / (PAC_BAND_HZ[1] - PAC_BAND_HZ[0]))", "np.sqrt(fs / (PAC_BAND_HZ[1] - PAC_BAND_HZ[0]))",
           ("emulator/tests/test_mount_vibration.py::test_the_pac_band_carries_the_given_rms_from_the_start_on",),
           "a mount vibration's RMS in the PAC band is √2 too large (its density spread over fs, not fs/2)"),
    Mutant("mount-vibrations-do-not-add", "rig", "emulator/extrinsic.py",
           "variance[t >= start_s] += level ** 2", "variance[t >= start_s] = level ** 2",
           ("emulator/tests/test_mount_vibration.py::test_two_mount_vibrations_add_in_power",),
           "a second mount vibration replaces the first instead of adding its power"),
    Mutant("stepper-level-the-same-every-trial", "rig", "bench/rigs/texture_rig.py",
           "return s.stepper_noise_Pa * math.exp(s.stepper_noise_log_spread * z)", "return s.stepper_noise_Pa",
           ("emulator/tests/test_mount_vibration.py::test_the_rig_draws_each_trials_stepper_level_from_its_seed",),
           "the stepper's background is the same in every trial (D: \"not consistent from trial to trial\")"),
    Mutant("a-bad-value-hides-the-overrun", "scenes", "bench/scenes/scene.py",
           "        if dur is not None:  # its span is checked whatever its force",
           "        if dur is not None and peak is not None:  # its span is checked whatever its force",
           ("bench/tests/test_hostile_input.py",),
           "a tap with a bad peak_N is not checked for running past the scene's end (one problem reported of two)"),
    Mutant("a-bad-texture-hides-the-slide-overrun", "scenes", "bench/scenes/scene.py",
           "    if None in [vals[k] for k in timing]:", "    if tex is None or None in [vals[k] for k in timing]:",
           ("bench/tests/test_hostile_input.py",),
           "a slide with an unknown texture is not checked for running past the scene's end"),
    Mutant("stage-cache-misses-the-textures-package", "experiment", "bench/experiments/experiment.py",
           'packages = ("emulator", "bench/rigs", "bench/textures", "bench/running")',
           'packages = ("emulator", "bench/rigs", "bench/running")',
           ("bench/tests/test_sweep_review2.py::test_the_stage_cache_key_digests_every_module_a_trial_runs_through",),
           "the stage cache key leaves out the motor-current law and the library's units: old trials replayed"),
    Mutant("validation-reuses-training-seeds", "experiment", "bench/experiments/experiment.py",
           'trial_seed(spec.seed, "validation", tex, int(m), k)', 'trial_seed(spec.seed, "training", tex, int(m), k)',
           ("bench/tests/test_sweep_review2.py::test_validation_trials_are_new_trials_not_the_training_ones_again",),
           "validation trials repeat their training twins' start positions and noise (accuracy inflated)"),
    Mutant("oblique-ridges-met-more-often", "textures", "emulator/texture.py",
           "return self.period_m / max(c, 1e-3)", "return self.period_m * max(c, 1e-3)",
           ("emulator/tests/test_texture_tracks.py::test_an_oblique_component_is_met_less_often_along_the_track",),
           "an oblique grating's period along the track is p·cos θ instead of p / cos θ"),
    Mutant("self-affine-slope-halved", "textures", "emulator/texture.py",
           "(q / q0) ** -(1 + 2 * texture.hurst)", "(q / q0) ** -(1 + texture.hurst)",
           ("emulator/tests/test_texture_tracks.py::test_the_random_track_is_self_affine_with_the_textures_hurst_exponent",),
           "the random relief's spectrum falls as q^-(1+H) instead of q^-(1+2H)"),
    Mutant("viscous-friction-dropped", "sliding", "emulator/sliding.py",
           "tex.mu_per_velocity_s_per_m, *(x[i:j]", "0.0, *(x[i:j]",
           ("emulator/tests/test_sliding.py::test_the_viscous_friction_rise_reaches_the_sliding_force",),
           "the sliding kernel drops the textures' viscous friction rise µ_v·v"),
    Mutant("stage-corner-200Hz", "sliding", "emulator/sliding.py",
           "STAGE_CORNER_HZ = 20.0", "STAGE_CORNER_HZ = 200.0",
           ("emulator/tests/test_sliding.py::test_the_stage_feels_the_tangential_force_through_its_20_hz_low_pass",),
           "the stage's motor current follows the tangential force up to 200 Hz, not 20 Hz"),
    Mutant("friction-lowers-the-pressure", "sliding", "emulator/sliding.py",
           "normal + p.tangential_coupling * tang", "normal - p.tangential_coupling * tang",
           ("emulator/tests/test_sliding.py::test_the_mean_friction_raises_the_fluid_pressure_by_the_coupling",),
           "the mean friction lowers the fluid pressure instead of raising it"),
    Mutant("slide-ramps-linear", "sliding", "emulator/sliding.py",
           "return self.force_N * (0.5 - 0.5 * np.cos(np.pi * up))", "return self.force_N * up",
           ("emulator/tests/test_sliding.py::test_a_slides_force_ramps_are_raised_cosines",),
           "a slide's approach ramps linearly instead of as a raised cosine"),
    Mutant("soft-layer-never-densifies", "sliding", "emulator/friction.py",
           "k_tex = k_flat * math.exp(min(n0 / (k_flat * layer_m), 50.0))", "k_tex = k_flat",
           ("emulator/tests/test_friction_solver.py::test_a_soft_texture_layer_stiffens_as_it_densifies",),
           "a soft texture layer keeps its flat-punch stiffness as it compresses toward its thickness"),
    Mutant("traces-need-e1", "reports", "bench/reporting/plots.py",
           'if any(f"E{n}" in names for n in range(1, 25)):', 'if "E1" in names:',
           ("bench/tests/test_report_readability.py::test_a_frame_of_electrodes_without_e1_still_gets_its_traces",),
           "a frame of electrodes without E1 writes no traces.png"),
    Mutant("rig-radius-table-too-short", "rig", "emulator/sliding.py",
           "COMMANDED_FORCE_MAX_N = 5.0", "COMMANDED_FORCE_MAX_N = 0.5",
           ("bench/tests/test_texture_rig.py::test_the_patch_radius_table_covers_the_load_of_the_rigs_heaviest_movement",),
           "the rig's patch-radius table stops at 1.25 N: the patch stops growing above it"),
    Mutant("skin-contact-stiffness-prefactor-1", "sliding", "emulator/friction.py",
           "return 1.5 * K ** (2.0 / 3.0)", "return 1.0 * K ** (2.0 / 3.0)",
           ("emulator/tests/test_friction_solver.py::test_the_kernels_contact_stiffness_is_the_hertz_law_s_slope",),
           "the sliding kernel's contact stiffness 1.0·K^(2/3)·N^(1/3), not the Hertz law's 1.5"),
    Mutant("brownout-splits-a-held-window", "faults", "bench/hosts/cosim.py",
           "                while 0 < j < n and keep[j - 1]:", "                while False:",
           ("bench/tests/test_campaign_cases.py::test_a_reset_due_inside_a_held_window_waits_for_it_to_close",),
           "a timed reset splits a window the firmware holds open on one sensor (its held read then differs)"),
    Mutant("rtl-requests-while-busy", "rtl", "emulator/rtl/biotac_spi.v",
           "(^b0) && is_sampled(channel) && !busy;", "(^b0) && is_sampled(channel);",
           ("emulator/tests/test_rtl.py::test_cpp_harness_reproduces_every_golden_vector",),
           "the RTL asks the bench for a conversion while the ADC is busy (the command is answered E- all the same)"),
    Mutant("closed-figures-kept-until-later", "reporting", "bench/reporting/figures.py",
           "    gc.collect()  # earlier figures'", "    pass  # earlier figures'",
           ("bench/tests/test_run_memory_release.py::test_a_drawn_figure_is_freed_before_the_next_one_is_made",),
           "a run's closed figures stay in memory under the next one (the run's peak grows)"),
    # 2026-11-23: a mutation hunt in the least-covered modules (units, noise budget, creep, bridge, Cheetah, driver)
    Mutant("unit-drift-spread-x10", "units", "emulator/units.py", "DRIFT_SPREAD = 0.20", "DRIFT_SPREAD = 2.0",
           ("bench/tests/test_units.py::test_the_population_of_units_has_the_documented_spreads_each_drawn_independently",),
           "units' bridge drifts spread ±200 % (some drift the wrong way as the core warms)"),
    Mutant("unit-stage2-bias-shares-stage1s-draw", "units", "emulator/units.py",
           '_normal(seed, "stage2_bias"', '_normal(seed, "stage1_bias"', ("bench/tests/test_units.py::test_the_population_of_units_has_the_documented_spreads_each_drawn_independently",),
           "every unit's stage-2 bias is its stage-1 bias draw (PDC and PAC offsets perfectly correlated)"),
    Mutant("unit-tolerances-one-sided", "units", "emulator/units.py",
           "uniform(-half_width, half_width)", "uniform(0.0, half_width)", ("bench/tests/test_units.py::test_the_population_of_units_has_the_documented_spreads_each_drawn_independently",),
           "every unit's thermistor R25 and Beta drawn above nominal"),
    Mutant("budget-pa-on-the-pdc-scale", "noise", "emulator/noise_budget.py",
           "pa_per_bit = ADC_LSB_V / p.pac_V_per_Pa", "pa_per_bit = ADC_LSB_V / p.pdc_V_per_Pa",
           ("emulator/tests/test_channel_noise.py::test_the_budget_prints_pa_on_the_published_pac_scale",),
           "noise-budget prints Pa on the PDC scale (~99x too large)"),
    Mutant("budget-tac-without-its-gain", "noise", "emulator/noise_budget.py",
           "h_tac = TAC_GAIN * signal", "h_tac = signal",
           ("emulator/tests/test_channel_noise.py::test_the_thermistor_lines_are_what_the_running_thermal_network_measures",),
           "the budget's TAC line leaves out the x98 TAC gain"),
    Mutant("budget-tac-line-is-tdcs", "noise", "emulator/noise_budget.py",
           'v = tdc_V if name == "TDC" else tac_V', "v = tdc_V",
           ("emulator/tests/test_channel_noise.py::test_the_thermistor_lines_are_what_the_running_thermal_network_measures",),
           "the budget prints TDC's thermistor noise on the TAC line"),
    Mutant("budget-pdc-path-x10", "noise", "emulator/noise_budget.py",
           "to_pdc_bits = p.stage1_gain / ADC_LSB_V", "to_pdc_bits = p.stage1_gain * 10 / ADC_LSB_V",
           ("emulator/tests/test_channel_noise.py::test_the_pdc_path_line_is_the_intrinsic_noise_over_the_stage1_band_times_its_gain",),
           "the budget's PDC path lines 10x too large"),
    Mutant("budget-pac-total-drops-the-reference", "noise", "emulator/noise_budget.py",
           '+ ref["PAC"] ** 2 + p.pac_path_noise_rms_bits**2', "+ p.pac_path_noise_rms_bits**2",
           ("emulator/tests/test_channel_noise.py::test_every_total_is_the_quadrature_sum_of_the_lines_it_lists",),
           "PAC's total leaves out a line the budget lists (the reference noise)"),
    Mutant("creep-settle-forgets-the-preload", "skin", "emulator/viscoelastic.py",
           "self.state[:] = x0", "self.state[:] = 0.0",
           ("emulator/tests/test_skin_mechanics.py::test_a_settled_creep_holds_its_preload_without_creeping",),
           "a creep settled under a load creeps again after t = 0"),
    Mutant("creep-hold-coefficients-swapped", "skin", "emulator/viscoelastic.py",
           "b0, b1 = 1.0 - g, g - a", "b0, b1 = g - a, 1.0 - g",
           ("emulator/tests/test_skin_mechanics.py::test_creep_step_response_is_the_exact_exponential",),
           "the first-order-hold creep update weights this and the last sample the wrong way round"),
    Mutant("block-times-one-sample-late", "model", "emulator/effects.py",
           "return (self.n0 + np.arange(self.n)) / self.fs", "return (self.n0 + 1 + np.arange(self.n)) / self.fs",
           ("emulator/tests/test_model.py::test_a_blocks_sample_times_start_at_its_first_grid_index",),
           "time-driven effects see each sample one grid step late"),
    Mutant("bridge-settles-at-35-C", "thermal", "emulator/transducer.py",
           'return {"stage1_input_V": self.params.bridge_offset_at(t) + self.params.bridge_span_at(t) * p}',
           'return {"stage1_input_V": self.offset + self.span * p}',
           ("emulator/tests/test_model.py::test_the_bridge_settles_where_it_runs_whatever_the_core_temperature",),
           "a bridge starts at the 35 °C voltage whatever the core's temperature (a start-up transient)"),
    Mutant("cheetah-delay-cycles-x10-short", "cheetah", "emulator/cheetah/cheetah_emu.c",
           "(long long)cycles * 1000000LL / dev.bitrate_khz", "(long long)cycles * 100000LL / dev.bitrate_khz",
           ("firmware_tests/tests/test_cheetah_device.py::test_a_delay_in_cycles_lasts_that_many_periods_of_the_bit_clock",),
           "ch_spi_queue_delay_cycles idles the bus a tenth of the time asked"),
    Mutant("cheetah-ss2-polarity-dropped", "cheetah", "emulator/cheetah/cheetah_emu.c",
           "dev.ss_polarity = ss_polarity & 7", "dev.ss_polarity = ss_polarity & 3",
           ("firmware_tests/tests/test_cheetah_device.py::test_spi_settings_the_sensors_do_not_use_garble_the_traffic",),
           "the adapter ignores SS2's polarity bit"),
    Mutant("driver-electrode-names-off-by-one", "host", "bench/hosts/driver.py",
           '(f"E{c - 16}" for c', '(f"E{c - 17}" for c',
           ("firmware_tests/tests/test_driver_robustness.py::test_to_physical_converts_each_channel_and_leaves_bad_slots_nan",),
           "to_physical names the electrodes E0..E18"),
    Mutant("driver-bad-slots-converted", "host", "bench/hosts/driver.py",
           "codes[frame.status[:, k] != 0] = np.nan", "pass",
           ("firmware_tests/tests/test_driver_robustness.py::test_to_physical_converts_each_channel_and_leaves_bad_slots_nan",),
           "to_physical converts error words and parity failures as if they were codes"),
    # 2026-11-23: a second mutation hunt (exports, report, slide recorder, scene parser, rig)
    Mutant("npz-force-on-pacs-baseline", "outputs", "bench/reporting/exports.py",
           'pdc_to_force_n(codes, baselines["PDC"])', 'pdc_to_force_n(codes, baselines["PAC"])',
           ("bench/tests/test_exported_figures.py::test_the_force_column_reads_zero_at_rest_and_the_press_while_pressed",),
           "codes.npz's PDC_force_N measured from PAC's resting code (about -15 N at rest)"),
    Mutant("h5-rate-attribute-off", "outputs", "bench/reporting/store.py",
           "                                       / len(seq_idx))", "                                       / (len(seq_idx) + 1))",
           ("bench/tests/test_exported_figures.py::test_the_hdf5_rate_attribute_is_each_channels_sample_rate",),
           "samples.h5's rate_Hz attribute is not the channel's sampling rate"),
    Mutant("report-velocity-in-mm-per-s", "outputs", "bench/reporting/report.py",
           "{100 * r['velocity_m_per_s']:g}", "{1000 * r['velocity_m_per_s']:g}",
           ("bench/tests/test_exported_figures.py::test_the_report_prints_the_slides_velocity_in_cm_per_s",),
           "the report's sliding table prints mm/s under its cm/s header"),
    Mutant("report-detection-rate-denominator", "outputs", "bench/reporting/report.py",
           'd["detection_rate"] = d["detected"] / d["drops"]', 'd["detection_rate"] = d["detected"] / (d["drops"] + 1)',
           ("bench/tests/test_cli_and_runs.py::test_impact_detection_report_for_the_sphere_scene",),
           "the impact table's detection rate is not detected/drops (10 of 10 shows 91 %)"),
    Mutant("slide-contact-at-its-start", "sliding", "bench/running/slides.py",
           "s.start_s + s.approach_s, s.slide_start_s", "s.start_s, s.slide_start_s",
           ("bench/tests/test_exported_figures.py::test_a_slides_roughness_and_fineness_are_those_of_its_exported_codes",),
           "a scene's slide takes contact at its start, before the finger has come down"),
    Mutant("slide-keeps-bad-words", "sliding", "bench/running/slides.py",
           "& (t <= s.end_s) & (status == 0)", "& (t <= s.end_s)",
           ("bench/tests/test_exported_figures.py::test_the_slide_recorder_keeps_only_good_samples",),
           "error words and parity failures enter a slide's roughness and fineness"),
    Mutant("background-without-its-guard", "textures", "bench/textures/properties.py",
           "t0, t1 = rec.contact_s + guard_s, rec.slide_start_s - guard_s",
           "t0, t1 = rec.contact_s, rec.slide_start_s - guard_s",
           ("bench/tests/test_texture_properties.py::test_the_touchdown_transient_stays_out_of_the_background",),
           "the roughness background starts at contact: the touchdown ring inflates it"),
    Mutant("resting-sigma-without-the-mad-factor", "noise", "bench/running/aggregate.py",
           "float(1.4826 * (lo + hi) / 2.0)", "float((lo + hi) / 2.0)",
           ("bench/tests/test_exported_figures.py::test_the_resting_sigma_is_the_noise_without_a_quiet_lead_in",),
           "PAC's resting sigma without a quiet lead-in is the MAD, not sigma (1.48x low: false detections)"),
    Mutant("calibrator-kpa-read-as-pa", "scenes", "bench/scenes/scene.py",
           "PressureCalibrator(t, dur, offset * 1e3,", "PressureCalibrator(t, dur, offset,",
           ("bench/tests/test_exported_figures.py::test_the_pressure_calibrators_offset_is_in_kpa",),
           "a scene's pressure offset_kPa is taken as Pa"),
    Mutant("slide-end-without-its-acceleration", "scenes", "bench/scenes/scene.py",
           "            self.accel_s + self.lift_s", "            self.lift_s",
           ("bench/tests/test_exported_figures.py::test_a_slide_that_ends_after_the_scene_by_its_acceleration_is_refused",),
           "a slide overrunning the scene by its acceleration is accepted (then dropped from the results)"),
    Mutant("rig-wears-half-the-distance", "rig", "bench/rigs/texture_rig.py",
           "self.skin.wear(movement.force_N, s.distance_m,", "self.skin.wear(movement.force_N, 0.5 * s.distance_m,",
           ("bench/tests/test_texture_rig.py::test_a_trial_wears_the_skin_by_the_distance_it_slid",),
           "the rig wears the skin for half the distance it slid"),
    Mutant("line-corruption-shadowed-by-drops", "faults", "bench/hosts/bridge.py",
           "if r < self.drop_rate + self.corrupt_rate:", "if r < self.corrupt_rate:",
           ("firmware_tests/tests/test_faults.py::test_the_lines_corruption_and_drop_rates_are_each_their_own",),
           "with both line faults set, bytes are corrupted at corrupt_rate less drop_rate"),
    Mutant("fluid-damping-grows-with-the-layer", "mechanics", "emulator/mechanics.py",
           "damping = p.fluid_viscosity_Pa_s * p.skin_load_area_m2 / h", "damping = p.fluid_viscosity_Pa_s * p.skin_load_area_m2 * h",
           ("emulator/tests/test_skin_mechanics.py::test_the_fluid_layer_thins_as_the_finger_empties_and_shears_harder",),
           "the fluid layer's damping grows with its thickness (Couette shear falls with it)"),
    Mutant("electrode-creep-not-settled", "electrodes", "emulator/electrodes.py",
           "            cr.settle(c.resting_load_N())", "            pass",
           ("emulator/tests/test_electrode_locality.py::test_a_contact_held_since_before_the_start_does_not_creep_after_it",),
           "a contact loaded before t = 0 creeps the electrodes for a second after it"),
    Mutant("bench-stimuli-to-every-sensor", "fingers", "bench/hosts/cosim.py",
           "stimuli=stimuli if k == 1 else ()", "stimuli=stimuli",
           ("firmware_tests/tests/test_driver_robustness.py::test_the_default_bench_sensors_each_have_their_own_noise_and_only_sensor_1_feels_the_stimuli",),
           "a bench's stimuli reach every default sensor, not sensor 1 alone"),
    Mutant("bench-sensors-share-a-seed", "fingers", "bench/hosts/cosim.py",
           "seed=seed + k, variant=variant", "seed=seed, variant=variant",
           ("firmware_tests/tests/test_driver_robustness.py::test_the_default_bench_sensors_each_have_their_own_noise_and_only_sensor_1_feels_the_stimuli",),
           "a bench's default sensors share one noise seed (identical noise on every finger)"),
    Mutant("spectrogram-nyquist-row-doubled", "outputs", "bench/running/aggregate.py",
           "            p[:, 1:-1] *= 2", "            p[:, 1:] *= 2",
           ("bench/tests/test_exported_figures.py::test_the_streamed_spectrogram_is_scipys_column_for_column",),
           "the spectrogram's Nyquist row is doubled (3 dB high in spectrogram.png)"),
    Mutant("spectrogram-columns-early", "outputs", "bench/running/aggregate.py",
           "times = self.t0 + (self.nper / 2 + (self._segments", "times = self.t0 + ((self._segments",
           ("bench/tests/test_exported_figures.py::test_the_streamed_spectrogram_is_scipys_column_for_column",),
           "the spectrogram's columns sit at their windows' starts: events show 40 ms early"),
    Mutant("late-drops-left-out", "outputs", "bench/reporting/report.py",
           "if s.time_s + rule.window_s > rec.simulated_s:", "if s.time_s + rule.window_s >= rec.simulated_s - 0.1:",
           ("bench/tests/test_exported_figures.py::test_a_drop_is_counted_when_its_100_ms_window_fits_in_the_run",),
           "the impact table leaves out drops in the run's last 100 ms whose window still fits"),
    Mutant("electrode-map-rest-from-half-the-run", "outputs", "bench/running/aggregate.py",
           "self.early_end_s = 0.05 * self.duration_s", "self.early_end_s = 0.5 * self.duration_s",
           ("bench/tests/test_exported_figures.py::test_the_electrode_maps_resting_codes_are_the_first_twentieth_of_the_run",),
           "the electrode map's resting codes include pressed ones (the first half of the run, not the first 5 %)"),
    Mutant("npz-tac-with-tdc-at-its-own-instants", "outputs", "bench/reporting/exports.py",
           "                tdc = _interp(r.times, d.times, d.codes)", "                tdc = _interp(d.times, d.times, d.codes)[:r.times.size]",
           ("bench/tests/test_exported_figures.py::test_tac_in_the_exports_uses_tdc_interpolated_at_each_tac_instant",),
           "codes.npz converts TAC with TDC taken at TDC's instants, not interpolated at TAC's"),
    Mutant("h5-failed-append-not-cut-back", "outputs", "bench/reporting/store.py",
           "                    d.resize((k,))", "                    pass",
           ("bench/tests/test_run_full_disk.py::test_a_disk_full_mid_stream_keeps_every_sample_taken_before_it",),
           "a write that fails on a full disk leaves a channel's instants longer than its codes in the kept samples"),
    Mutant("h5-buffer-dropped-before-written", "outputs", "bench/reporting/store.py",
           "            lst[:] = [tuple(arrays)]\n", "            lst.clear()\n",
           ("bench/tests/test_run_full_disk.py::test_a_disk_full_mid_stream_keeps_every_sample_taken_before_it",),
           "samples leave the buffer before they are written: a full disk loses them"),
    Mutant("h5-salvage-keeps-the-failed-chunk", "outputs", "bench/reporting/store.py",
           "            before = t < until_s", "            before = t <= t",
           ("bench/tests/test_run_full_disk.py::test_a_disk_full_mid_stream_keeps_every_sample_taken_before_it",),
           "samples.h5 kept after a full disk holds samples past the instant the run stopped"),
    Mutant("lock-on-a-removed-file-kept", "outputs", "bench/reporting/outdir.py",
           "    if not same:  # its holder", "    if False:  # its holder",
           ("bench/tests/test_cli_followups.py::test_a_lock_removed_by_its_holder_while_it_was_being_taken_is_taken_afresh",),
           "a lock taken on a file its holder removed meanwhile locks nothing: two campaigns write one report"),
    Mutant("lead-in-keeps-error-words", "outputs", "bench/running/aggregate.py",
           "                m = (tc < LEAD_IN_S) & (sc == 0)", "                m = (tc < LEAD_IN_S)",
           ("bench/tests/test_exported_figures.py::test_error_words_in_the_lead_in_never_reach_the_baseline",),
           "error words and parity errors in the resting lead-in move the baselines every conversion subtracts"),
    Mutant("every-finger-slides-from-seed-1", "scenes", "bench/scenes/scene.py",
           "own, int(seed) + k - 1, wear,", "own, int(seed), wear,",
           ("bench/tests/test_multi_finger.py::test_each_finger_draws_its_slides_start_positions_from_its_own_seed",),
           "every finger's slides start where finger 1's do: sensor k does not draw from seed + k - 1"),
    Mutant("rig-stage-starts-a-latency-late", "sliding", "bench/rigs/texture_rig.py",
           "motion.move_stage(slide_start - s.latency_s, v, acc)", "motion.move_stage(slide_start, v, acc)",
           ("bench/tests/test_texture_rig.py::test_the_stage_starts_at_the_recorded_slide_start",),
           "the stage moves a latency after the slide start the recording names: the properties' windows are shifted"),
    Mutant("pressure-amplitude-without-frequency-accepted", "scenes", "bench/scenes/scene.py",
           "if amp is not None and freq is not None and amp > 0 and freq == 0:", "if False:",
           ("bench/tests/test_hostile_input.py",),
           "a pressure stimulus with an amplitude and no frequency is not refused by name (it would do nothing)"),
    Mutant("minimum-gap-above-resting-accepted", "scenes", "emulator/params.py",
           "        if self.minimum_gap_mm >= self.resting_gap_mm:", "        if False:",
           ("bench/tests/test_hostile_input.py", "bench/tests/test_scene_combinations.py"),
           "a sensor whose skin bottoms further from the core than it rests is accepted: its electrodes respond backwards"),
    Mutant("impact-detection-on-finger-1-only", "scenes", "bench/scenes/scene.py",
           "                                   and any(isinstance(s, SphereDrop) for s in sp.stimuli))",
           "                                   and k == 1)",
           ("bench/tests/test_multi_finger.py::test_impact_detection_judges_the_drops_of_every_finger",),
           "D's detection rule is applied to sensor 1's drops only: another finger's drops go unjudged"),
    Mutant("force-clears-at-open", "outputs", "bench/cli/experiments.py",
           "    return OutFolder.open(path, force=force, kind=kind, keep=keep, defer_clearing=True)",
           "    return OutFolder.open(path, force=force, kind=kind, keep=keep)",
           ("bench/tests/test_sweep_review.py::test_force_keeps_the_earlier_results_until_the_new_ones_are_written",),
           "explore/texture-sweep --force remove the earlier results before the new ones exist: a failure loses both"),
    Mutant("force-never-clears-the-earlier-results", "outputs", "bench/cli/experiments.py",
           "                folder.clear_earlier()  # (once: the baseline's results come first)",
           "                pass",
           ("bench/tests/test_sweep_review.py::test_explore_protects_its_results_and_reruns_from_the_cache",),
           "explore --force leaves the earlier results (an ablation folder of the earlier run) beside the new ones"),
    Mutant("experiment-pairs-at-the-identification-threshold", "exploration", "bench/experiments/experiment.py",
           'threshold=spec.pair_threshold,', 'threshold=spec.identification_threshold,',
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "the pairs are explored to 99 % instead of D's 99.9 %"),
    Mutant("experiment-pair-simulations-doubled", "exploration", "bench/experiments/experiment.py",
           'n_sims=spec.pair_simulations // 2,', 'n_sims=spec.pair_simulations,',
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "each pair runs twice the simulations the file asks for"),
    Mutant("experiment-baselines-are-bayesian", "exploration", "bench/experiments/experiment.py",
           'ident_results[s] = [ex.simulate(train, val_table, true, strategy=s,', 'ident_results[s] = [ex.simulate(train, val_table, true, strategy="bayesian",',
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "the identification's cycle and random baselines run the Bayesian strategy"),
    Mutant("experiment-cycle-ignores-the-pilots-picks", "exploration", "bench/experiments/experiment.py",
           '    all_ctx = ex.prepare(train, best_movements=best)', '    all_ctx = ex.prepare(train)',
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "the cycle baseline cycles movements re-derived from training, not the pilot's picks"),
    Mutant("exploration-stops-at-99-for-pairs", "exploration", "bench/experiments/exploration.py",
           'live[r] = post_r.max(axis=1) <= threshold', 'live[r] = post_r.max(axis=1) <= ABSOLUTE_THRESHOLD',
           ("bench/tests/test_exploration.py::test_a_simulation_stops_exactly_when_a_candidate_passes_the_threshold",),
           "a simulation stops at 99 % whatever its threshold"),
    Mutant("exploration-two-trials-get-the-floor", "exploration", "bench/experiments/exploration.py",
           'sigma = np.sqrt(np.where(n > 1,', 'sigma = np.sqrt(np.where(n > 2,',
           ("bench/tests/test_exploration.py::test_two_trials_give_the_sample_sigma_not_the_floor",),
           "a cell of two training trials gets the σ floor: an overconfident model"),
    Mutant("exploration-even-median-low", "exploration", "bench/experiments/exploration.py",
           's[int(np.ceil(mid))]', 's[int(np.floor(mid))]',
           ("bench/tests/test_exploration.py::test_median_moves_of_an_even_count_is_the_mean_of_the_middle_two",),
           "the median of an even count of simulations is the lower middle value"),
    Mutant("exploration-textures-share-draws", "exploration", "bench/experiments/exploration.py",
           'spawn_key=(int(true_texture), int(i))', 'spawn_key=(int(i),)',
           ("bench/tests/test_exploration.py::test_each_true_texture_draws_its_own_random_numbers",),
           "every true texture's simulations draw the same random numbers"),
    Mutant("campaign-tasks-never-retried", "campaigns", "bench/campaigns/engine.py",
           "retries=retries)", "retries=0)",
           ("bench/tests/test_campaign_engine.py::test_a_task_that_raises_once_is_retried_and_zero_workers_is_refused",),
           "a task that fails once (a transient error) fails the whole campaign"),
    Mutant("campaign-zero-workers-means-all", "campaigns", "bench/campaigns/engine.py",
           "spec.workers < 1:", "spec.workers < 0:",
           ("bench/tests/test_campaign_engine.py::test_a_task_that_raises_once_is_retried_and_zero_workers_is_refused",),
           "workers = 0 silently starts a LocalCluster of every core"),
    Mutant("campaign-sensor-found-again-unchecked", "campaigns", "bench/campaigns/faults.py",
           'if not (0b01 in masks and masks[-1] == 0b11):', 'if not (0b01 in masks):',
           ("bench/tests/test_campaign_cases.py::test_every_clause_of_a_check_objects_on_its_own",),
           "unplug/replug passes though sensor 2 never comes back"),
    Mutant("campaign-loss-counters-unchecked", "campaigns", "bench/campaigns/faults.py",
           'if status.losses < 1 or status.finds < 1:', 'if False:',
           ("bench/tests/test_campaign_cases.py::test_every_clause_of_a_check_objects_on_its_own",),
           "unplug/replug passes though the firmware counted no loss or find"),
    Mutant("campaign-parity-count-unchecked", "campaigns", "bench/campaigns/faults.py",
           ' or status.parity_errors == 0:', ':',
           ("bench/tests/test_campaign_cases.py::test_every_clause_of_a_check_objects_on_its_own",),
           "parity errors flagged but never counted by the firmware pass"),
    Mutant("campaign-reset-allows-20-bad", "campaigns", "bench/campaigns/faults.py",
           '    if bad > 2:', '    if bad > 20:',
           ("bench/tests/test_campaign_cases.py::test_every_clause_of_a_check_objects_on_its_own",),
           "a reset may corrupt up to 20 samples (the spec: at most two)"),
    Mutant("campaign-dropped-reset-sensor-passes", "campaigns", "bench/campaigns/faults.py",
           '        return "the reset sensor was dropped"', '        pass',
           ("bench/tests/test_campaign_cases.py::test_every_clause_of_a_check_objects_on_its_own",),
           "a reset sensor dropped from the bus passes"),
    Mutant("campaign-clean-ignores-flagged", "campaigns", "bench/campaigns/faults.py",
           'if stats.crc_errors or stats.dropped_frames or flagged:', 'if stats.crc_errors or stats.dropped_frames:',
           ("bench/tests/test_campaign_cases.py::test_every_clause_of_a_check_objects_on_its_own",),
           "a healthy link with flagged samples passes"),
    Mutant("campaign-junit-counts-passes", "campaigns", "bench/campaigns/faults.py",
           'failures=str(sum(not r["passed"] for r in results)),', 'failures=str(sum(r["passed"] for r in results)),',
           ("bench/tests/test_campaign_cases.py::test_the_junit_report_counts_its_failures",),
           "the JUnit report's failures attribute counts the passes"),
    Mutant("stage-cache-key-without-the-code", "exploration", "bench/experiments/experiment.py",
           "repr(tasks) + _code_digest()", "repr(tasks)",
           ("bench/tests/test_sweep_review2.py::test_the_stage_cache_runs_again_when_the_code_changes_or_its_rows_are_not_its_tasks",),
           "a warm stage cache replays old trials after the model's code changed"),
    Mutant("stage-cache-trusts-other-tasks-rows", "exploration", "bench/experiments/experiment.py",
           "any(row.get(k) != v for k, v in asdict(task).items()) or ", "",
           ("bench/tests/test_sweep_review2.py::test_the_stage_cache_runs_again_when_the_code_changes_or_its_rows_are_not_its_tasks",),
           "a cache file of the right length whose rows are other tasks' trials is trusted"),
    Mutant("object-first-half-layer-whole", "thermal", "emulator/thermal.py",
           "d[0] / (2 * mat.k * area)", "d[0] / (mat.k * area)",
           ("emulator/tests/test_thermal_electrodes.py::test_a_touched_object_draws_heat_as_a_semi_infinite_body", "emulator/tests/test_thermal_electrodes.py::test_a_touched_objects_steady_heat_flow_is_the_contact_and_slab_in_series"),
           "the touched object's first layer conducts from its far side: less heat drawn from the skin"),
    Mutant("object-far-field-a-whole-layer-away", "thermal", "emulator/thermal.py",
           "g_far[obj[-1]] = mat.k * area / (d[-1] / 2)", "g_far[obj[-1]] = mat.k * area / d[-1]",
           ("emulator/tests/test_thermal_electrodes.py::test_a_touched_object_draws_heat_as_a_semi_infinite_body", "emulator/tests/test_thermal_electrodes.py::test_a_touched_objects_steady_heat_flow_is_the_contact_and_slab_in_series"),
           "the object's far field sits a whole last layer beyond its centre: a slab too thick"),
    Mutant("thermal-expm-taylor-cut-short", "thermal", "emulator/thermal.py",
           "    for k in range(1, 13):", "    for k in range(1, 9):",
           ("emulator/tests/test_thermal_live_contact.py::test_expm_by_products_equals_scipys_on_the_networks_own_matrices",),
           "the live contact's matrix exponential keeps 8 Taylor terms, not 12: its thermal steps drift"),
    Mutant("force-log-phase-per-block", "sliding", "emulator/sliding.py",
           "keep = slice(-(block.n0 + a) % self.log_every, None, self.log_every)", "keep = slice(0, None, self.log_every)",
           ("emulator/tests/test_sliding.py::test_the_force_log_does_not_depend_on_block_size",),
           "the 100 Hz force log restarts its phase at each block: its instants depend on how the run is cut"),
    Mutant("library-friction-may-fall-with-speed", "sliding", "bench/textures/library.py",
           '"s/m", 0.0, 20.0', '"s/m", -20.0, 20.0',
           ("bench/tests/test_texture_library.py::test_broken_libraries_are_rejected_with_texture_field_and_value",),
           "a texture whose friction falls with speed (a negative viscous coefficient) is accepted"),
    Mutant("library-complete-without-t117", "sliding", "bench/textures/library.py",
           "missing = [n for n in range(1, LIBRARY_SIZE + 1) if n not in seen.numbers]",
           "missing = [n for n in range(1, LIBRARY_SIZE) if n not in seen.numbers]",
           ("bench/tests/test_texture_library.py::test_a_complete_library_needs_every_one_of_the_117",),
           "a 'complete' library missing T117 is accepted"),
    Mutant("centroid-segments-share-one-mean", "sliding", "bench/textures/properties.py",
           "seg.mean(axis=1, keepdims=True)", "seg.mean(axis=0, keepdims=True)",
           ("bench/tests/test_texture_properties.py::test_each_segment_loses_its_own_mean_so_a_drifting_pac_keeps_its_centroid",),
           "the centroid's segments are not each mean-removed: a drifting PAC drags fineness toward 0 Hz"),
    Mutant("trial-row-copies-the-commanded-force", "sliding", "bench/experiments/trials.py",
           "true_normal_N=trial.true_normal_N", "true_normal_N=task.force_N",
           ("bench/tests/test_texture_rig.py::test_a_trial_row_reports_the_force_the_rig_reached_not_the_one_it_was_told",),
           "the trial table's true normal force is the commanded one: force control looks perfect"),
    Mutant("most-confused-picks-the-least", "exploration", "bench/experiments/experiment.py",
           "sorted(cands, reverse=True)", "sorted(cands)",
           ("bench/tests/test_experiment_report_picks.py::test_most_confused_pairs_are_the_pairs_the_model_confuses_most",),
           "pair_choice = \"most-confused\" picks the least confused pairs"),
    Mutant("stepper-noise-a-tenth", "exploration", "bench/experiments/design.py",
           'lambda spec: {"stepper_noise_Pa": 0.52}', 'lambda spec: {"stepper_noise_Pa": 0.052}',
           ("bench/tests/test_experiment.py::test_the_stepper_noise_ablation_is_the_sensors_own_resting_pac_noise_in_pascals",),
           "the stepper-noise ablation runs at a tenth of the sensor's own resting PAC noise"),
    Mutant("pilot-u-on-the-wrong-rows", "exploration", "bench/experiments/experiment.py",
           "u_full[model.movements] = u", "u_full[:len(u)] = u",
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "the pilot's uncertainty table lands on the first rows, not the movements the pilot ran"),
    Mutant("validation-on-a-fresh-skin", "exploration", "bench/experiments/experiment.py",
           "        session, history = schedule_skin(tasks + val_tasks, wear=spec.wear, replace_at=replace_at)\n"
           "        tasks = session[len(tasks):]",
           "        tasks, history = schedule_skin(val_tasks, wear=spec.wear, replace_at=replace_at)",
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "validation starts on a fresh skin instead of going on with the training session's worn one"),
    Mutant("touch-on-a-chunk-start-arrives-late", "thermal", "emulator/thermal.py",
           " and (c0 is None or c0 is self._touching)\n", "\n",
           ("emulator/tests/test_thermal_electrodes.py::test_a_touch_on_a_whole_second_meets_its_object_at_once",),
           "an object touched exactly at a thermal chunk's start meets the skin a whole second late"),
    Mutant("object-arrives-at-the-previous-temperature", "thermal", "emulator/thermal.py",
           "            x[4:] = contact.temperature_C\n", "            pass\n",
           ("emulator/tests/test_thermal_electrodes.py::test_the_first_response_to_a_touch_scales_with_the_objects_own_temperature",),
           "a touched object's layers start at the previous temperature, not the object's own"),
    Mutant("wear-table-trials-to-visible-one-short", "sliding", "bench/experiments/trials.py",
           "int(np.ceil(visible_m / per_trial))", "int(np.floor(visible_m / per_trial))",
           ("bench/tests/test_texture_rig.py::test_the_wear_table_agrees_with_a_skin_worn_trial_by_trial",),
           "wear.csv says the first visible wear comes a trial sooner than the skin shows it"),
    Mutant("wear-table-per-second-without-velocity", "sliding", "bench/experiments/trials.py",
           '"lost_per_second_m": per_trial * m.velocity_m_per_s / distance_m', '"lost_per_second_m": per_trial / distance_m',
           ("bench/tests/test_texture_rig.py::test_the_wear_table_agrees_with_a_skin_worn_trial_by_trial",),
           "wear.csv's loss per second ignores how long a trial lasts at its velocity"),
    Mutant("library-cache-keyed-on-size-alone", "sliding", "bench/textures/library.py",
           "st.st_mtime_ns, st.st_size", "0, st.st_size",
           ("bench/tests/test_texture_library.py::test_an_edited_library_file_is_read_again_even_at_the_same_size",),
           "an edited library file of the same size returns the old textures from the cache"),
    Mutant("most-confused-at-tractions-movement", "exploration", "bench/experiments/experiment.py",
           "conf[:, :, mi[p], p]", "conf[:, :, mi[0], p]",
           ("bench/tests/test_experiment_report_picks.py::test_most_confused_reads_each_property_at_its_own_best_movement",),
           "most-confused pairs read every property's confusion at traction's best movement"),
    Mutant("validation-runs-training-trials", "exploration", "bench/experiments/experiment.py",
           "for k in range(spec.validation_trials)]", "for k in range(spec.training_trials)]",
           ("bench/tests/test_sweep_review2.py::test_validation_runs_the_validation_trials_it_is_asked_for",),
           "the validation stage runs as many trials as training, not the validation trials asked for"),
    Mutant("rig-load-blind-to-heights", "sliding", "emulator/friction.py",
           "                if touching == 0 and touchdown_reference:  # touchdown",
           "                if touchdown_reference:  # touchdown",
           ("emulator/tests/test_sliding.py::test_a_position_held_finger_feels_the_heights_it_slides_over",),
           "a position-held finger's load ignores the heights it slides over: the rig's normal force never fluctuates"),
    Mutant("depth-law-without-poisson", "sliding", "emulator/sliding.py",
           "    k = 2.0 * radius * modulus / (1 - POISSON_RATIO**2)", "    k = 2.0 * radius * modulus",
           ("emulator/tests/test_sliding.py::test_the_depth_law_uses_the_textures_plane_strain_modulus",),
           "the rig's depth-to-load law uses E, not the kernel's E/(1 - nu^2): soft textures 9 % stiffer"),
    Mutant("ridge-release-counts-only-its-first-drop", "sliding", "emulator/friction.py",
           "        return 0, extreme - force\n", "        return 0, 0.0\n",
           ("emulator/tests/test_ridge_release.py::test_an_events_releases_add_up_to_its_peak_to_trough_drop",),
           "a ridge release's released force is only its first drop, not the whole peak-to-trough"),
    Mutant("rechord-keeps-a-stale-peak", "sliding", "emulator/friction.py",
           "        ridge_state[1, j] *= stiffness / before", "        pass",
           ("emulator/tests/test_ridge_release.py::test_a_shorter_chord_scales_the_counts_peak_a_longer_one_the_deflection",),
           "a ridge whose chord shortens keeps its release count's old peak: spurious or missed release events"),
    Mutant("live-patch-radius-floored", "thermal", "emulator/thermal.py",
           "np.rint(radius / PATCH_RADIUS_STEP_M)", "np.floor(radius / PATCH_RADIUS_STEP_M)",
           ("emulator/tests/test_thermal_live_contact.py::test_the_live_patch_radius_is_rounded_to_the_nearest_step",),
           "the live contact's patch radius is rounded down, biasing every thermal patch small"),
    Mutant("slip-out-is-the-last-substeps", "sliding", "emulator/friction.py",
           "        out_slip_velocity[n] = vr_sum / substeps", "        out_slip_velocity[n] = vr",
           ("emulator/tests/test_friction_fluctuation.py::test_the_slip_velocity_out_is_each_grid_steps_mean_over_its_substeps",),
           "the slip velocity reported per grid step is the last substep's, not the step's mean"),
    Mutant("surface-track-starts-at-minus-start", "sliding", "emulator/texture.py",
           "np.roll(heights, -int(", "np.roll(heights, int(",
           ("emulator/tests/test_texture_tracks.py::test_a_track_starting_further_on_is_the_same_surface_shifted_and_reads_between_samples_linearly",),
           "surface_track starts at -start on the texture, not at start"),
    Mutant("surface-track-reads-backwards", "sliding", "emulator/texture.py",
           "return self.heights_m[i] * (1 - f) + self.heights_m[(i + 1) % n] * f",
           "return self.heights_m[i] * f + self.heights_m[(i + 1) % n] * (1 - f)",
           ("emulator/tests/test_texture_tracks.py::test_a_track_starting_further_on_is_the_same_surface_shifted_and_reads_between_samples_linearly",),
           "SurfaceTrack.at interpolates between samples backwards"),
    Mutant("crest-table-margin-half-the-box", "sliding", "emulator/sliding.py",
           "margin = max(1, int(round(skin.ridge_contact_width_m / dx_m))) + 2",
           "margin = max(1, int(round(skin.ridge_contact_width_m / dx_m))) // 2",
           ("emulator/tests/test_sliding.py::test_the_crest_table_reads_each_position_as_the_whole_surface_would",),
           "the crest table's pieces are computed with half the box as margin: the gradient beside each seam reads "
           "the box average's edge"),
    Mutant("crest-table-wrap-one-position-late", "sliding", "emulator/sliding.py",
           "(ahead, first + ahead - n_track, n - ahead)", "(ahead, first + ahead - n_track + 1, n - ahead)",
           ("emulator/tests/test_sliding.py::test_the_crest_table_reads_each_position_as_the_whole_surface_would",),
           "the crest table's wrapped indices read one position on from the ones just before the track's start"),
    Mutant("campaign-accepts-a-tenth-of-the-frames", "campaign", "bench/campaigns/faults.py",
           "elif len(frames) < frames_wanted // 2:", "elif len(frames) < frames_wanted // 20:",
           ("bench/tests/test_campaign_cases.py::test_a_fault_that_silences_the_stream_fails_the_case_saying_how_many_frames_came",),
           "a case whose stream fell silent after a tenth of its frames is judged on them"),
    Mutant("campaign-pac-range-13-bits", "campaign", "bench/campaigns/faults.py",
           "pac.max() <= 4095", "pac.max() <= 4096",
           ("bench/tests/test_campaign_cases.py::test_a_code_past_12_bits_from_the_driver_fails_the_case",),
           "a 13-bit PAC code from the driver passes the campaign"),
    Mutant("leak-check-band-30-percent-low", "campaign", "bench/campaigns/faults.py",
           "min(drops) / 1.15 - 2 <=", "min(drops) / 1.3 - 2 <=",
           ("bench/tests/test_campaign_leak.py",),
           "the leak check takes a leak 25 % slower than the fault's"),
    Mutant("leak-check-band-30-percent-high", "campaign", "bench/campaigns/faults.py",
           "<= max(drops) * 1.15 + 2:", "<= max(drops) * 1.3 + 2:",
           ("bench/tests/test_campaign_leak.py",),
           "the leak check takes a leak 25 % faster than the fault's"),
    Mutant("leak-check-on-a-quarter-of-the-frames", "campaign", "bench/campaigns/faults.py",
           "if len(good) < 4 * LEAK_CASE_FRAMES:", "if len(good) < LEAK_CASE_FRAMES:",
           ("bench/tests/test_campaign_leak.py::test_the_leak_check_refuses_a_run_without_enough_clean_pdc",),
           "the leak check compares medians of frames too close together to measure a leak by"),
    Mutant("slides-share-one-motor-current-stream", "sliding", "bench/running/slides.py",
           'f"slide[{k}].motor_current"', '"slide.motor_current"',
           ("bench/tests/test_scene_slide.py::test_each_slide_reads_the_motor_current_through_its_own_noise",),
           "every slide of a scene reads its motor current through the same noise"),
    Mutant("overrun-frames-miss-an-eaten-crc", "host", "bench/hosts/bridge.py",
           "ranges[k][0] < end and", "ranges[k][0] < end - 2 and",
           ("firmware_tests/tests/test_uart_overrun.py::test_a_frame_that_lost_only_its_crc_is_counted_lost",),
           "overrun_frames() leaves out a frame the overrun took only the CRC of"),
    Mutant("centroid-segments-512", "textures", "bench/textures/properties.py",
           "CENTROID_WINDOW, CENTROID_OVERLAP = 256, 0.5", "CENTROID_WINDOW, CENTROID_OVERLAP = 512, 0.5",
           ("bench/tests/test_properties_definitions.py::test_the_centroids_spectrum_is_welchs_with_256_sample_hann_segments_at_half_overlap",),
           "the spectral centroid's segments are 512 samples, not the README's 256"),
    Mutant("centroid-symmetric-hann", "textures", "bench/textures/properties.py",
           "seg = (seg - seg.mean(axis=1, keepdims=True)) * _hann(n)",
           "seg = (seg - seg.mean(axis=1, keepdims=True)) * np.hanning(n)",
           ("bench/tests/test_properties_definitions.py::test_the_centroids_spectrum_is_welchs_with_256_sample_hann_segments_at_half_overlap",),
           "the centroid's segments are tapered by the symmetric Hann window, not the periodic one"),
    Mutant("summary-order-statistic-one-low", "outputs", "bench/running/aggregate.py",
           'return int(np.searchsorted(np.cumsum(hist), k, side="right"))', 'return int(np.searchsorted(np.cumsum(hist), k, side="left"))',
           ("bench/tests/test_run_summary.py",),
           "the histogram's k-th value is read one count early: medians a code low where a code's count ends"),
    Mutant("summary-median-upper-middle-twice", "outputs", "bench/running/aggregate.py",
           'lo, hi = _hist_order_stat(hist, (n - 1) // 2), _hist_order_stat(hist, n // 2)', 'lo, hi = _hist_order_stat(hist, n // 2), _hist_order_stat(hist, n // 2)',
           ("bench/tests/test_run_summary.py",),
           "an even count's median is its upper middle value, not the mean of the two"),
    Mutant("summary-mad-upper-middle", "outputs", "bench/running/aggregate.py",
           'return float(1.4826 * (lo + hi) / 2.0)', 'return float(1.4826 * hi)',
           ("bench/tests/test_run_summary.py",),
           "the MAD σ of an even count takes the upper middle deviation"),
    Mutant("summary-std-sample-not-population", "outputs", "bench/running/aggregate.py",
           'var = max(0.0, (n * s2 - s1 * s1) / (n * n))', 'var = max(0.0, (n * s2 - s1 * s1) / (n * (n - 1)))',
           ("bench/tests/test_run_summary.py",),
           "record.json's std_code is a different estimator from the documented one (numpy's population σ)"),
    Mutant("summary-rate-counts-good-samples-only", "outputs", "bench/running/aggregate.py",
           '"rate_Hz": float(self.samples / simulated_s) if simulated_s else 0.0,', '"rate_Hz": float(self.good / simulated_s) if simulated_s else 0.0,',
           ("bench/tests/test_run_summary.py",),
           "a channel's rate leaves out its flagged samples, as if the bus had sampled it less"),
    Mutant("summary-envelope-bin-ends", "outputs", "bench/running/aggregate.py",
           'return ((nz + 0.5) * width,', 'return ((nz + 1.0) * width,',
           ("bench/tests/test_run_summary.py",),
           "the traces plot's envelope is drawn half a bin late"),
    Mutant("csv-tac-without-the-next-blocks-tdc", "outputs", "bench/reporting/exports.py",
           'nxt = store.read_channel(h5, "TDC", tdc_seen + d.times.size, tdc_seen + d.times.size + 1)',
           'nxt = store.read_channel(h5, "TDC", tdc_seen + d.times.size, tdc_seen + d.times.size)',
           ("bench/tests/test_outputs.py::test_csv_export_is_the_same_whatever_its_time_blocks",),
           "samples.csv converts a block's last TAC samples with the block's last TDC, not the one after them"),
    Mutant("roughness-background-until-the-slide", "textures", "bench/textures/properties.py",
           "t0, t1 = rec.contact_s + guard_s, rec.slide_start_s - guard_s",
           "t0, t1 = rec.contact_s + guard_s, rec.slide_start_s",
           ("bench/tests/test_texture_properties.py::test_the_stage_starting_stays_out_of_the_background",),
           "the roughness background runs up to the slide's start: the stage starting inflates it"),
    Mutant("report-accuracy-percent-as-fraction", "experiment", "bench/reporting/experiment_report.py",
           '"accuracy_%": round(100 * v["accuracy"], PERCENT_DECIMALS)', '"accuracy_%": round(v["accuracy"], PERCENT_DECIMALS)',
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "accuracy.csv holds fractions under accuracy_%"),
    Mutant("report-trials-without-validation", "experiment", "bench/reporting/experiment_report.py",
           'rows = result.pilot_rows + result.training_rows + result.validation_rows', 'rows = result.pilot_rows + result.training_rows',
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "trials.csv and trials.json leave out the validation trials"),
    Mutant("report-u-roughness-column-is-fineness", "experiment", "bench/reporting/experiment_report.py",
           '"U_roughness": result.pilot_uncertainty[m, 1]', '"U_roughness": result.pilot_uncertainty[m, 2]',
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "pilot_uncertainty.csv's U_roughness holds fineness's U"),
    Mutant("report-ridge-loss-in-mm", "experiment", "bench/reporting/experiment_report.py",
           'result.wear[m]["ridge_lost_m"] * 1e6', 'result.wear[m]["ridge_lost_m"] * 1e3',
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "pilot_uncertainty.csv's ridge loss in mm under a µm column"),
    Mutant("report-replacements-one-high", "experiment", "bench/reporting/experiment_report.py",
           'default=1) - 1,', 'default=1),',
           ("bench/tests/test_experiment.py::test_quick_experiment_runs_end_to_end_and_caches_its_stages",),
           "summary.json counts the first skin as a replacement"),
    Mutant("report-replace-at-when-never-replaced", "experiment", "bench/reporting/experiment_report.py",
           '"replace_at": spec.replace_at if spec.replace_skin else None', '"replace_at": spec.replace_at',
           ("bench/tests/test_experiment_report_picks.py::test_the_skin_policy_says_never_replaced_when_replacement_is_off",),
           "the report states a replacement level for an experiment that never replaces the skin"),
]

#: A quick sample of the catalogue that runs in the test suite (bench/tests/test_mutants.py): a few seconds each.
FAST = ("boltzmann-x10", "host-ignores-byte1-parity", "mux-memory-deleted", "tdc-bandwidth-2Hz")


def by_name(names) -> list[Mutant]:
    known = {m.name: m for m in CATALOGUE}
    unknown = [n for n in names if n not in known]
    if unknown:
        raise KeyError(f"unknown mutant(s): {', '.join(unknown)}; known: {', '.join(known)}")
    return [known[n] for n in names]


def check_catalogue(repo: Path = REPO, mutants=None) -> list[str]:
    """Problems with the catalogue against ``repo``: snippets not found exactly once, missing test files,
    duplicate names."""
    problems = []
    mutants = CATALOGUE if mutants is None else mutants
    names = [m.name for m in mutants]
    problems += [f"duplicate mutant name {n!r}" for n in sorted({n for n in names if names.count(n) > 1})]
    for m in mutants:
        path = repo / m.file
        if not path.exists():
            problems.append(f"{m.name}: {m.file} does not exist")
            continue
        count = path.read_text(encoding="utf-8").count(m.original)
        if count != 1:
            problems.append(f"{m.name}: the snippet occurs {count} times in {m.file} (must be exactly once)")
        if m.original == m.replacement:
            problems.append(f"{m.name}: the replacement equals the original")
        for t in m.tests:
            test_file, _, test_name = t.partition("::")
            if not (repo / test_file).exists():
                problems.append(f"{m.name}: test file {test_file} does not exist")
            elif test_name and f"def {test_name.split('[')[0]}(" not in (repo / test_file).read_text(encoding="utf-8"):
                problems.append(f"{m.name}: no test {test_name.split('[')[0]} in {test_file}")
    return problems


# --- scratch copies -------------------------------------------------------------------------------------
#: Without git (an unpacked archive), everything except these folders and files is copied.
_NOT_SOURCE = {".git", ".venv", ".tox", "out", "build", "__pycache__", ".pytest_cache", ".hypothesis"}


def tree_files(repo: Path = REPO) -> list[str]:
    """The working tree's files that git tracks or would track (untracked but not ignored), relative paths."""
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=repo,
                             capture_output=True, check=True).stdout
        return sorted({p for p in out.decode().split("\0") if p})
    except (OSError, subprocess.CalledProcessError):
        return sorted(str(p.relative_to(repo)) for p in Path(repo).rglob("*")
                      if (p.is_file() or p.is_symlink()) and not _NOT_SOURCE & set(p.relative_to(repo).parts)
                      and not p.name.endswith((".pyc", ".egg-info")) and ".egg-info" not in str(p))


def make_scratch(repo: Path = REPO, dest: Path | None = None) -> Path:
    """Copy the working tree's files (as they are on disk) into ``dest`` (a new temporary folder by default)."""
    dest = Path(dest or tempfile.mkdtemp(prefix="biotac-mutants-"))
    for rel in tree_files(repo):
        src = repo / rel
        if not src.exists() and not src.is_symlink():  # deleted in the working tree
            continue
        target = dest / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        if src.is_symlink():
            target.symlink_to(os.readlink(src))
        else:
            shutil.copy2(src, target)
    return dest


def scratch_env(scratch: Path) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(scratch) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def check_imports_from(scratch: Path) -> None:
    """Raise unless a Python started the way the tests are started imports ``emulator`` and ``bench`` from the
    scratch copy (not from the checkout the editable install points at)."""
    code = "import emulator, bench, bench.pytest_plugin.fixtures as f; print(emulator.__file__); print(bench.__file__); print(f.__file__)"
    r = subprocess.run([sys.executable, "-c", code], cwd=scratch, env=scratch_env(scratch), capture_output=True,
                       text=True)
    paths = r.stdout.split()
    root = str(Path(scratch).resolve())
    if r.returncode != 0 or len(paths) != 3 or not all(str(Path(p).resolve()).startswith(root) for p in paths):
        raise RuntimeError(f"the scratch copy's modules are not the ones imported: {r.stdout} {r.stderr}")


def run_pytest(scratch: Path, tests, timeout_s: float) -> tuple[int | None, str, float]:
    """(exit code or None on timeout, last lines of output, seconds) of pytest on ``tests`` in ``scratch``."""
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "--no-header", "-p", "no:cacheprovider", *tests]
    t0 = time.perf_counter()
    try:
        r = subprocess.run(cmd, cwd=scratch, env=scratch_env(scratch), capture_output=True, text=True,
                           timeout=timeout_s)
    except subprocess.TimeoutExpired:
        return None, f"timed out after {timeout_s:.0f} s", time.perf_counter() - t0
    tail = "\n".join((r.stdout + r.stderr).strip().splitlines()[-3:])
    return r.returncode, tail, time.perf_counter() - t0


def compiled_dependents(scratch: Path, rel: str) -> list[Path]:
    """The scratch copy's modules with numba-compiled functions that import the module at ``rel`` (a path in the
    tree).  Numba's on-disk cache is keyed on a function's own source file only, and a compiled function freezes the
    globals it reads (another module's constants) into its machine code: a mutant in ``rel`` reaches their cached
    code only if their caches are invalidated too."""
    if not rel.endswith(".py"):
        return []
    module = rel[:-3].replace("/", ".").removesuffix(".__init__")
    package, _, name = module.rpartition(".")
    imports = re.compile(rf"^\s*(import {re.escape(module)}\b|from {re.escape(module)} import|"
                         rf"from {re.escape(package)} import .*\b{name}\b|from \.{name} import|"
                         rf"from \. import .*\b{name}\b)", re.M)
    out = []
    for other in sorted(Path(scratch).rglob("*.py")):
        if other == Path(scratch) / rel or "tests" in other.relative_to(scratch).parts:
            continue
        text = other.read_text(encoding="utf-8")
        if ("njit" in text or "@jit" in text) and imports.search(text):
            out.append(other)
    return out


def _invalidate_compiled(paths) -> None:
    """Give ``paths`` a new modification time, so numba recompiles their cached functions on next use."""
    for p in paths:
        os.utime(p, ns=(time.time_ns(), time.time_ns()))


def run_mutant(scratch: Path, m: Mutant, timeout_s: float = 900.0) -> Result:
    path = Path(scratch) / m.file
    text = path.read_text(encoding="utf-8")
    if text.count(m.original) != 1:
        return Result(m.name, m.area, m.file, "error", 0.0,
                      f"snippet found {text.count(m.original)} times in {m.file} (must be exactly once)")
    dependents = compiled_dependents(scratch, m.file)
    path.write_text(text.replace(m.original, m.replacement), encoding="utf-8")
    _invalidate_compiled(dependents)  # their cached code may hold the unmutated module's constants
    try:
        code, tail, seconds = run_pytest(scratch, m.tests, timeout_s)
    finally:
        path.write_text(text, encoding="utf-8")
        _invalidate_compiled(dependents)  # ... and now the mutated ones
    if code == 1:
        return Result(m.name, m.area, m.file, "caught", seconds, _failed_line(tail))
    if code == 0:
        return Result(m.name, m.area, m.file, "survived", seconds, "every selected test passed")
    return Result(m.name, m.area, m.file, "error", seconds, tail)  # not collected, usage error, or timed out


def _failed_line(tail: str) -> str:
    lines = [ln for ln in tail.splitlines() if ln.startswith("FAILED")]
    return (lines[0] if lines else tail.splitlines()[-1] if tail else "")[:160]


def baseline(scratch: Path, mutants, timeout_s: float = 1800.0) -> tuple[bool, str]:
    """Run the union of the mutants' selections unmutated: they must all pass."""
    tests = sorted({t for m in mutants for t in m.tests})
    code, tail, _ = run_pytest(scratch, tests, timeout_s)
    return code == 0, tail


def run_catalogue(mutants=None, repo: Path = REPO, timeout_s: float = 900.0, keep: bool = False,
                  progress=None, check_baseline: bool = True) -> list[Result]:
    mutants = list(CATALOGUE if mutants is None else mutants)
    scratch = make_scratch(repo)
    try:
        check_imports_from(scratch)
        if check_baseline:
            if progress:
                progress(f"baseline: {len({t for m in mutants for t in m.tests})} test selection(s), unmutated")
            ok, tail = baseline(scratch, mutants)
            if not ok:
                raise RuntimeError(f"the selected tests fail without any mutation (fix them first):\n{tail}")
        results = []
        for i, m in enumerate(mutants, 1):
            if progress:
                progress(f"[{i}/{len(mutants)}] {m.name}")
            results.append(run_mutant(scratch, m, timeout_s))
            if progress:
                r = results[-1]
                progress(f"    {r.status} in {r.seconds:.1f} s")
        return results
    finally:
        if keep:
            if progress:
                progress(f"scratch copy kept in {scratch}")
        else:
            shutil.rmtree(scratch, ignore_errors=True)


def format_results(results: list[Result]) -> str:
    w = max([len(r.name) for r in results] + [6])
    lines = [f"{'mutant':{w}s}  {'area':10s} {'file':38s} {'result':9s} {'time':>7s}"]
    for r in results:
        lines.append(f"{r.name:{w}s}  {r.area:10s} {r.file:38s} {r.status:9s} {r.seconds:6.1f}s")
    counts = {s: sum(r.status == s for r in results) for s in ("caught", "survived", "error")}
    lines.append(f"{len(results)} mutants: {counts['caught']} caught, {counts['survived']} survived, "
                 f"{counts['error']} error")
    for r in results:
        if r.status != "caught":
            lines.append(f"  {r.name}: {r.status}: {r.detail}")
    return "\n".join(lines)


def format_list(mutants) -> str:
    w = max(len(m.name) for m in mutants)
    lines = [f"{'mutant':{w}s}  {'area':10s} {'file':38s} what it breaks"]
    lines += [f"{m.name:{w}s}  {m.area:10s} {m.file:38s} {m.what}" for m in mutants]
    lines.append(f"{len(mutants)} mutants")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="scripts/mutants", description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--list", action="store_true", help="list the catalogue and exit")
    ap.add_argument("--only", action="append", metavar="NAME", help="run this mutant (repeatable)")
    ap.add_argument("--fast", action="store_true", help=f"run the quick sample ({', '.join(FAST)})")
    ap.add_argument("--json", action="store_true", help="print the results as JSON")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per mutant (default 900)")
    ap.add_argument("--no-baseline", action="store_true", help="skip the unmutated run of the selected tests")
    ap.add_argument("--keep", action="store_true", help="keep the scratch copy (its path is printed)")
    a = ap.parse_args(argv)
    names = list(a.only or []) + (list(FAST) if a.fast else [])
    try:
        mutants = by_name(names) if names else list(CATALOGUE)
    except KeyError as e:
        print(f"error: {e.args[0]}", file=sys.stderr)
        return 2
    if a.list:
        print(json.dumps([asdict(m) for m in mutants], indent=2) if a.json else format_list(mutants))
        return 0
    problems = check_catalogue(mutants=mutants)
    if problems:
        print("error: the catalogue does not match the tree:\n  " + "\n  ".join(problems), file=sys.stderr)
        return 2
    progress = None if a.json else (lambda s: print(s, file=sys.stderr, flush=True))
    try:
        results = run_catalogue(mutants, timeout_s=a.timeout, keep=a.keep, progress=progress,
                                check_baseline=not a.no_baseline)
    except RuntimeError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(json.dumps([r.as_dict() for r in results], indent=2) if a.json else format_results(results))
    return 0 if all(r.status == "caught" for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())

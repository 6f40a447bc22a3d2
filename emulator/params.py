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

BOLTZMANN_J_PER_K = 1.380649e-23
ZERO_CELSIUS_K = 273.15

#: the LuGre bristle damping σ1 (s/m) a sensor can have, per N·s/m of the skin's tangential damping c_t: at the
#: scene limit of 20 N the bristles' damping N·σ1 stays within 200 times the skin's (measured, SensorParams'
#: bristle_damping_per_N comment: at nominal σ0 a 20 N, 0.5 m/s slide's mean friction on the fast, default and
#: reference grids agrees within 1.0 % at N·σ1/c_t = 200 — σ1 = 30 with c_t = 3, σ1 = 10 with c_t = 1, 0.4 % —
#: and 2.0, 3.0 and 4.0 % at 267, 333 and 400 — σ1 = 40 and 50 with c_t = 3, 20 with c_t = 1; at 200 with c_t =
#: 10, 30, 300 and 1e4 — σ0 = 1e5, 1e6, 1e7 and 1e9 — 1.1, 0.3, 0.0 and 0.1 %; the textures had µv = 0, which a
#: texture's viscous rise only helps).  A massless skin moves at force / c_t, so each spike of the damping term
#: moves the slip, which the damping term feeds on in turn (derived here: the step's residual loses its monotony
#: once N·σ1 times the relative fall of µ the bristles meet exceeds c_t + N·µv — LuGre's passivity condition,
#: see bristle_damping_per_N, with c_t/N added to the viscous term)
BRISTLE_DAMPING_PER_SKIN_DAMPING_PER_N = 10.0

#: below this bristle stiffness (1/m) the bristle damping allowed per skin damping falls in proportion: softer
#: bristles relax over a longer slip (µ/σ0), across larger falls of the friction's fluctuation (measured with
#: N·σ1/c_t = 67, σ1 = 10 and c_t = 3: σ0 = 1e5, 3.3e4, 1e4, 1e3 and 1e2 gave grids 0.3, 0.5, 3.3, 21 and 19 %
#: apart; with σ0 = 1e4, σ1 = 3: 0.4 %; σ0 = 3.3e4, σ1 = 10, c_t = 1: 5.2 %)
BRISTLE_DAMPING_FULL_STIFFNESS_PER_M = 1e5

#: the bristles' damping time σ1/σ0 (s) a sensor can have, whatever the skin's damping (measured: 1 ms with
#: σ0 = 1e4, c_t = 100 and σ0 = 1e5, c_t = 10 gave grids 0.0 and 1.1 % apart, and with c_t = 1e4 and σ0 = 3e4,
#: 1e3 and 1e2, 0.1, 0.0 and 0.1 %; σ0 = 1e5, σ1 = 1e5, c_t = 1e4 — 1 s — 25 %)
BRISTLE_DAMPING_TIME_MAX_S = 1e-3


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
    force_knee_N: float = _p(2.0, "N", 0.1, 20.0, "D", "force where the skin meets the core and the slope falls")
    force_slope_above_knee: float = _p(
        0.25, "1", 0.0, 1.0, "model", "pressure slope above the knee as a fraction of the slope below")
    force_knee_width_N: float = _p(0.08, "N", 0.01, 2.0, "model", "smoothness of the transition at the knee")
    resonance_Hz: float = _p(330.0, "Hz", 200.0, 350.0, "D", "skin/fluid resonance at nominal inflation")
    resonance_decay_s: float = _p(0.020, "s", 0.002, 0.2, "D", "decay time constant of impact ringing")
    displacement_zero_Hz: float = _p(
        500.0, "Hz", 50.0, 1e4, "model", "zero of the displacement path (direct transmission through the liquid)")
    impact_restitution: float = _p(0.3, "1", 0.0, 1.0, "model", "coefficient of restitution of a sphere on the skin")
    duct_resonance_Hz: float = _p(
        18.7e3, "Hz", 5e3, 1e5, "D", "closed-tube resonance of the 2 cm fluid duct, v/(4L) (reference profile only)")
    duct_quality_factor: float = _p(5.0, "1", 0.5, 100.0, "model", "quality factor of the duct resonance")

    # --- sliding contact (SENSOR.md §7; emulator/sliding.py) ---------------------------------
    contact_stiffness_N_per_m1_5: float = _p(
        17.2e3, "N/m^1.5", 1e2, 1e7, "model",
        "Hertz-like fingertip contact law N = K·δ^1.5 (1 N at 1.5 mm indentation)")
    contact_radius_at_1N_m: float = _p(
        2.5e-3, "m", 1e-4, 2e-2, "model", "radius of the contact patch on a flat surface at 1 N (grows as N^(1/3))")
    skin_tangential_stiffness_N_per_m: float = _p(
        1500.0, "N/m", 10.0, 1e6, "model", "tangential stiffness of the skin over the fluid (pre-slip ramp)")
    # (at least 1 N·s/m: the skin is massless, so without damping its velocity is undetermined while it slides
    # steadily — the friction then does not depend on it — and its slips shrink to one grid step: at 0 a 20 N,
    # 0.5 m/s slide's mean friction was 4.6 N on the reference grid and 16.0 N on the default one; from 1 N·s/m the
    # two agree within 2.5 % for skin stiffnesses of 1e3 to 1e6 N/m, at 0.3 they still differed by 11 %)
    skin_tangential_damping_N_s_per_m: float = _p(
        3.0, "N·s/m", 1.0, 1e4, "model", "tangential damping of the skin (2 ms with the stiffness)")
    bristle_stiffness_per_N: float = _p(
        1e5, "1/m", 1e2, 1e9, "model", "LuGre bristle stiffness per N of load (micro-slip ~ µ/σ0 ≈ 10 µm)")
    # (at most 30 s/m, and less with less skin damping or softer bristles: see bristle_damping_limit_s_per_m.
    # Criterion: a 20 N, 0.5 m/s slide — the scene limits' corner — keeps its mean friction within µk·N·0.9 …
    # µs·N·1.1, opposing the slip, and the same within 2 % on the fast, default and reference grids.  The damping
    # term N·σ1·dz/dt is a one-step spike wherever the bristles relax within a step, and through the massless skin
    # (velocity = force / c_t) it moves the slip: measured at nominal σ0 and c_t (means fast / default / reference,
    # N; smooth µ 1.0/0.8 and a 3 mm grating µ 0.6/0.45): σ1 = 10: 16.07/16.08/16.12 and 9.02/9.03/9.05; 30:
    # 16.08/16.08/16.11 and 9.03/9.04/8.95 (1.0 % apart); 50: 3.0 %; 100: 10 % (8.10 on the reference); 1e3: peaks
    # 57/123/2027 N; 1e4: the grating's mean 0.7 N on the fast grid; 1e5: 88 N on smooth, −39 and −45 N on the
    # grating (fast, default); these limits were measured with a constant σ1 and are kept).  The passivity
    # condition of LuGre with a constant σ1 (the subject of Barabanov & Ortega, IEEE TAC 45(4) 2000; derived here
    # in this model's per-newton units, not checked against the paper's own statement) reads σ1 ≤ µv·µk/(µs − µk)
    # (σ0 drops out): 0 for 63 of the library's 119 textures (µv = 0) and at most 4.0 s/m (float glass), below the
    # nominal 10 for every texture — and the breach showed: at a slip's onset the friction pushed the skin along
    # the slip (−7.7 N at 20 N, 20 cm/s) and gave back up to 1.4e-4 J in a step, and a 20 N, 0.5 m/s slide's mean
    # friction on the reference's ridge-resolved sand kept moving as the step shrank (9.87 N at 114 µs, 10.80 at
    # the reference's 3.55, 10.96 at 1.78).  So σ1 is the damping at rest and fades with slip, σ1·exp(−(v_r/v_s)²)
    # (Olsson et al. 1998's remedy, emulator.friction._bristle_damping): the element then dissipates at every step
    # while σ1·v_s/√(2e) ≤ 4·µk (0.064 against ≥ 1.3 over the library; tested), and that mean converges (11.05,
    # 11.42, 11.42 N))
    bristle_damping_per_N: float = _p(
        10.0, "s/m", 0.0, 30.0, "model", "LuGre bristle damping per N of load")
    tangential_coupling: float = _p(
        0.5, "1", 0.0, 2.0, "model",
        "fluid pressure from tangential force as a fraction of the pressure from the same normal force")

    # --- piezoresistive bridge (SENSOR.md §3) ------------------------------------------
    bridge_excitation_V: float = _p(10.0, "V", 1.0, 15.0, "D", "bridge supply")
    bridge_sensitivity_V_per_V_Pa: float = _p(0.218e-6, "V/(V·Pa)", 1e-8, 1e-5, "D", "0.218 mV/V·kPa")
    bridge_resistance_ohm: float = _p(5e3, "Ω", 100.0, 1e6, "D", "output resistance (Johnson noise source)")
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

    # --- thermal network and thermistor (SENSOR.md §4) -------------------------------------
    ambient_temperature_C: float = _p(25.0, "°C", -20.0, 60.0, "D", "room temperature")
    heater_rise_K: float = _p(10.0, "K", 0.0, 30.0, "D", "heaters hold the core about 10 °C above ambient")
    core_heat_capacity_J_per_K: float = _p(6.0, "J/K", 0.1, 100.0, "model", "epoxy core with electronics")
    fluid_heat_capacity_J_per_K: float = _p(1.75, "J/K", 0.01, 20.0, "model", "0.5 mL of water/glycol")
    skin_heat_capacity_J_per_K: float = _p(2.0, "J/K", 0.01, 20.0, "model", "silicone skin")
    thermistor_heat_capacity_J_per_K: float = _p(0.004, "J/K", 1e-5, 1.0, "model", "thermistor bead")
    core_fluid_conductance_W_per_K: float = _p(0.1, "W/K", 1e-3, 10.0, "model", "core surface to fluid")
    fluid_skin_conductance_W_per_K: float = _p(0.2, "W/K", 1e-3, 10.0, "model", "fluid layer to skin")
    thermistor_conductance_W_per_K: float = _p(
        0.004, "W/K", 1e-4, 1.0, "model", "bead to its surroundings (dissipation constant): ~1 s time constant")
    skin_air_conductance_W_per_K: float = _p(0.015, "W/K", 1e-4, 1.0, "model", "convection from the skin")
    mount_conductance_W_per_K: float = _p(0.015, "W/K", 0.0, 1.0, "model", "core to the finger's mount")
    contact_conductance_W_per_m2K: float = _p(
        3000.0, "W/(m²·K)", 10.0, 1e6, "model", "skin-to-object contact conductance")
    tdc_bandwidth_Hz: float = _p(22.6, "Hz", 1.0, 49.0, "D", "TDC bandwidth (Table 4-1)")
    tac_highpass_Hz: float = _p(0.45, "Hz", 0.01, 10.0, "D", "TAC high-pass (Table 4-1; the text says 5 Hz)")
    tdc_noise_V: float = _p(
        0.3e-6, "V", 0.0, 1e-2, "model",
        "RMS noise of the thermistor divider node per 10 ms step: its Johnson noise (30 kΩ ∥ 303 kΩ at 35 °C over "
        "the steps' 50 Hz: 0.15 µV) and the buffer's (~20 nV/√Hz, 1/f corner 10 Hz: 0.21 µV), rounded up")

    # --- electrodes (SENSOR.md §5) ---------------------------------------------------------
    electrode_load_ohm: float = _p(10e3, "Ω", 100.0, 1e6, "D", "R_load on the multiplexer output")
    electrode_series_ohm: float = _p(1.55e3, "Ω", 0.0, 1e5, "model", "electrode interface and spreading")
    fluid_sheet_ohm_mm: float = _p(3.85e3, "Ω·mm", 1.0, 1e6, "model", "fluid layer resistance × thickness")
    resting_gap_mm: float = _p(1.5, "mm", 0.2, 5.0, "model", "fluid thickness over the electrodes at rest")
    minimum_gap_mm: float = _p(0.1, "mm", 0.01, 1.0, "model", "fluid left when the skin bottoms on the core")
    indentation_force_N: float = _p(1.5, "N", 0.05, 50.0, "model", "force for 63 % of the maximum indentation")
    skin_spread_mm: float = _p(3.0, "mm", 0.5, 10.0, "model", "how far an indentation spreads in the skin")
    shear_shift_mm_per_N: float = _p(1.0, "mm/N", 0.0, 10.0, "model", "pattern shift per N of tangential force")
    electrode_bandwidth_Hz: float = _p(100.0, "Hz", 1.0, 400.0, "D", "electrode channel bandwidth")
    mux_settling_s: float = _p(4e-6, "s", 1e-8, 1e-3, "model", "multiplexer and hold-node settling")
    mux_acquisition_s: float = _p(20e-6, "s", 1e-7, 1e-3, "model", "firmware delay from mux switch to conversion")
    mux_injection_V: float = _p(0.05, "V", 0.0, 1.0, "model", "charge injected into the hold node at a switch")

    # --- ADC (SENSOR.md §2) ------------------------------------------------------------
    adc_conversion_s: float = _p(
        5e-6, "s", 1e-7, 1e-4, "model",
        "ADC acquisition and conversion window after a command; SPI clocking inside it couples into the sample")
    adc_noise_rms_bits: float = _p(
        0.45, "LSB", 0.0, 20.0, "model",
        "ADC input (transition) noise per conversion, common to every channel: the 12-bit SAR's ENOB (11.1 typ., "
        "dsPIC33FJ datasheet) less quantization and the reference share; see the per-channel noise section")

    # --- extrinsic noise (SENSOR.md §3) ------------------------------------------------
    mains_frequency_Hz: float = _p(60.0, "Hz", 40.0, 70.0, "D", "mains frequency (60 Hz in the source lab)")
    mains_amplitude_V: float = _p(
        0.516e-6, "V", 0.0, 1e-3, "model",
        "hum amplitude of the fundamental at the first-stage input; gives the 0.2 bits² largest 2 Hz band of PAC "
        "at rest (harmonics: mains_harmonic2_ratio, mains_harmonic3_ratio)")
    spi_coupling_rms_V: float = _p(
        4.0e-3, "V", 0.0, 0.1, "model", "ADC-input disturbance when a conversion overlaps SPI clocking")

    # --- sensor units (issue 10.1; emulator/units.py draws these per unit) -------------------
    electrode_gap_spread_mm: float = _p(
        0.0, "mm", 0.0, 1.0, "model", "spread of each electrode's resting fluid gap around resting_gap_mm (0: alike)")
    electrode_gap_seed: float = _p(
        0, "1", 0, 2**31 - 1, "model", "whole number seeding the per-electrode resting gaps (a unit's own draw)")
    thermistor_r25_ohm: float = _p(
        470e3, "Ω", 1e3, 1e7, "D",
        "thermistor resistance at 25 °C (Vishay NTCS0805E3474FXT, D ch. 4: 470 kΩ ±1 %); a unit's own value")
    thermistor_beta_K: float = _p(
        4025.0, "K", 2000.0, 6000.0, "model",
        "thermistor Beta (equivalent of D eq. 4.4; the part's B25/85 tolerance is ±3 %); a unit's own value")

    # --- per-channel noise (issue 10.2; emulator/adc.py, emulator/extrinsic.py) -----------------
    adc_reference_noise_ppm: float = _p(
        20.0, "ppm", 0.0, 1e4, "model",
        "RMS noise of the ADC reference (VREFH = AVDD, 3.3 V) per conversion, relative: a code k moves by k·ppm·1e-6 "
        "(≈ 66 µV RMS, the order of a 3.3 V LDO's output noise over the conversion bandwidth)")
    pac_path_noise_rms_bits: float = _p(
        1.04, "LSB", 0.0, 20.0, "model",
        "extra noise of the PAC path only (second gain stage and ADC driver, sampled per conversion); CALIBRATED: "
        "the one knob sized so PAC at rest reads D's measured 1.4 bits RMS")
    mains_harmonic2_ratio: float = _p(
        0.04, "1", 0.0, 1.0, "model",
        "2nd mains harmonic (120 Hz at 60 Hz mains) amplitude / fundamental at the stage-1 input: capacitive "
        "pickup grows as n·V_n; IEC 61000-2-2 compatibility level V_2 = 2 % gives 2 × 2 %")
    mains_harmonic3_ratio: float = _p(
        0.15, "1", 0.0, 1.0, "model",
        "3rd mains harmonic (180 Hz at 60 Hz mains) amplitude / fundamental at the stage-1 input: capacitive "
        "pickup grows as n·V_n; IEC 61000-2-2 compatibility level V_3 = 5 % gives 3 × 5 %")

    # --- skin viscoelasticity, contact mechanics and impacts (issues 10.4, 10.5, 11.2) -----------
    skin_load_area_m2: float = _p(
        2.5e-4, "m²", 2e-5, 1.5e-3, "model",
        "effective area of the skin membrane over the fluid that a contact loads (ventral pad ~14 × 18 mm)")
    skin_direct_stiffness_N_per_m: float = _p(
        160.0, "N/m", 0.0, 1e5, "model",
        "relaxed stiffness of the skin shell carrying load to the core/nail directly (not through the fluid); "
        "calibrated: sets 11.5 mN/PDC bit at the published bridge, gain and ADC")
    skin_relaxation_time_s: float = _p(
        1.0, "s", 1e-3, 100.0, "model", "stress-relaxation time of the silicone skin (standard linear solid)")
    skin_relaxed_modulus_fraction: float = _p(
        0.6, "1", 0.3, 1.0, "model",
        "relaxed/instantaneous modulus E∞/E0 of the filled silicone skin (sets creep and hysteresis of PDC); "
        "calibrated: R² of a 0–2 N press-and-release near D's 0.995")
    skin_youngs_modulus_Pa: float = _p(
        0.97e6, "Pa", 1e4, 1e8, "model",
        "skin Young's modulus: Silastic S (D ch. 4), ~26 Shore A, through Gent's hardness relation")
    skin_poisson_ratio: float = _p(0.5, "1", 0.0, 0.5, "model", "skin Poisson ratio (incompressible elastomer)")
    skin_density_kg_per_m3: float = _p(1120.0, "kg/m³", 500.0, 3000.0, "model", "silicone skin density")
    fluid_density_kg_per_m3: float = _p(
        1150.0, "kg/m³", 500.0, 3000.0, "model",
        "BioTac fluid: 82 % polyethylene glycol, 18 % water, 1 M NaBr (D ch. 4)")
    fluid_viscosity_Pa_s: float = _p(
        0.035, "Pa·s", 1e-4, 10.0, "model", "viscosity of the glycol solution at the ~35 °C core temperature")
    fluid_wetted_area_m2: float = _p(
        1.0e-3, "m²", 1e-4, 5e-3, "model",
        "core area under the skin; the fluid layer is inflation volume / this area (0.5 mm at 0.5 mL)")

    # --- local electrodes (issue 10.3; emulator/electrodes.py) ---------------------------------
    bulge_width_ratio: float = _p(
        0.7071, "1", 0.3, 5.0, "model",
        "rim-bulge ring width s over the indentation width w; the ring peaks at √2·s = w, just outside the contact")
    free_skin_half_angle_deg: float = _p(
        120.0, "deg", 60.0, 180.0, "model",
        "skin free to bulge within this angle of the ventral midline; beyond it the skin is tethered at the nail")

    # ------------------------------------------------------------------------------
    @property
    def bridge_temperature_C(self) -> float:
        """The bridge sits in the heated core: ambient + heater rise when settled."""
        return self.ambient_temperature_C + self.heater_rise_K

    @property
    def bridge_temperature_K(self) -> float:
        return self.bridge_temperature_C + ZERO_CELSIUS_K

    @property
    def resonance_at_inflation_Hz(self) -> float:
        """Skin/fluid resonance at the present inflation: √(k/m)/2π from the fluid and skin stiffness and the
        moving mass (emulator/mechanics.py); ``resonance_Hz`` anchors it at the nominal 0.5 mL."""
        from emulator.mechanics import skin_fluid

        return skin_fluid(self).resonance_Hz

    @property
    def bristle_damping_limit_s_per_m(self) -> float:
        """The most LuGre bristle damping σ1 (s/m) this sensor's bristle stiffness σ0 and skin damping c_t allow:
        :data:`BRISTLE_DAMPING_PER_SKIN_DAMPING_PER_N` × c_t × min(1, σ0 /
        :data:`BRISTLE_DAMPING_FULL_STIFFNESS_PER_M`), and σ0 × :data:`BRISTLE_DAMPING_TIME_MAX_S` (30 s/m at the
        nominal values, the range's top)."""
        s0, ct = self.bristle_stiffness_per_N, self.skin_tangential_damping_N_s_per_m
        return min(BRISTLE_DAMPING_PER_SKIN_DAMPING_PER_N * ct * min(1.0, s0 / BRISTLE_DAMPING_FULL_STIFFNESS_PER_M),
                   BRISTLE_DAMPING_TIME_MAX_S * s0)

    @property
    def resting_pressure_Pa(self) -> float:
        """Resting (DC) fluid pressure from the inflation volume."""
        return self.resting_pressure_at(self.inflation_volume_mL)

    def resting_pressure_at(self, volume_mL):
        """Resting fluid pressure (Pa) at an inflation volume (mL, scalar or array; P = a·V^n)."""
        return self.resting_pressure_Pa_per_mL * volume_mL ** self.resting_pressure_exponent

    def bridge_span_at(self, temperature_C):
        """Bridge output per Pa (V/Pa) at a bridge temperature (°C, scalar or array)."""
        dT = temperature_C - self.bridge_reference_temperature_C
        return self.bridge_excitation_V * self.bridge_sensitivity_V_per_V_Pa * (1.0 + self.bridge_span_drift_per_K * dT)

    def bridge_offset_at(self, temperature_C):
        """Bridge zero-pressure output (V) at a bridge temperature (°C, scalar or array)."""
        dT = temperature_C - self.bridge_reference_temperature_C
        return self.bridge_excitation_V * (self.bridge_offset_V_per_V + self.bridge_offset_drift_V_per_V_K * dT)

    @property
    def bridge_span_V_per_Pa(self) -> float:
        """Bridge output per Pa at the settled core temperature."""
        return self.bridge_span_at(self.bridge_temperature_C)

    @property
    def bridge_offset_V(self) -> float:
        return self.bridge_offset_at(self.bridge_temperature_C)

    @property
    def johnson_noise_V_per_rtHz(self) -> float:
        """√(4kTR) of the bridge output resistance at the bridge temperature."""
        return math.sqrt(4.0 * BOLTZMANN_J_PER_K * self.bridge_temperature_K * self.bridge_resistance_ohm)

    @property
    def force_to_pressure_Pa_per_N(self) -> float:
        """Quasi-static (relaxed) fluid pressure per N of contact force, from contact mechanics: the fraction
        of the load the fluid carries over the loaded skin area (emulator/mechanics.py).  The bridge, gain and
        ADC do not enter: mN per PDC bit follows from this slope and that chain."""
        from emulator.mechanics import skin_fluid

        return skin_fluid(self).pressure_per_N_relaxed

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
        changed = dataclasses.replace(self, **changes)
        problems = changed.inconsistencies()
        if problems:
            raise ValueError("; ".join(problems))
        return changed

    def inconsistencies(self, where: str = "sensor") -> list[str]:
        """What no sensor can be though each value is within its own range (``where``: the table's name)."""
        problems = []
        if self.minimum_gap_mm >= self.resting_gap_mm:
            problems.append(f"{where}.minimum_gap_mm = {self.minimum_gap_mm:g} mm must be below {where}.resting_gap_mm"
                            f" = {self.resting_gap_mm:g} mm (the fluid left when the skin bottoms is less than at "
                            f"rest)")
        limit = self.bristle_damping_limit_s_per_m
        if self.bristle_damping_per_N > limit * (1.0 + 1e-12):
            problems.append(
                f"{where}.bristle_damping_per_N = {self.bristle_damping_per_N:g} s/m is more than the bristle "
                f"stiffness and skin damping allow: at most {limit:.4g} s/m with {where}.bristle_stiffness_per_N = "
                f"{self.bristle_stiffness_per_N:g} 1/m and {where}.skin_tangential_damping_N_s_per_m = "
                f"{self.skin_tangential_damping_N_s_per_m:g} N·s/m ({BRISTLE_DAMPING_PER_SKIN_DAMPING_PER_N:g}/N × "
                f"the skin damping × min(1, σ0 / {BRISTLE_DAMPING_FULL_STIFFNESS_PER_M:g} 1/m), and σ1/σ0 at most "
                f"{BRISTLE_DAMPING_TIME_MAX_S * 1e3:g} ms; beyond, a slide's mean friction depends on the "
                f"simulation grid)")
        if self.electrode_gap_seed != int(self.electrode_gap_seed):
            problems.append(f"{where}.electrode_gap_seed = {self.electrode_gap_seed!r}: must be a whole number "
                            f"(0 to {2**31 - 1})")
        return problems


PARAMETER_FIELDS = {f.name: f for f in dataclasses.fields(SensorParams)}


def check_parameter(name: str, value, where: str, spell=repr) -> None:
    """Raise ValueError naming ``where``, the value and the allowed range if ``value`` is out of range; ``spell``
    writes the value (Python's ``repr``; a scene file's caller passes its TOML spelling)."""
    meta = PARAMETER_FIELDS[name].metadata
    lo, hi = meta["range"]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{where} = {spell(value)}: must be a finite number in {meta['unit']} ({lo} to {hi})")
    if not lo <= value <= hi:
        raise ValueError(f"{where} = {spell(value)} {meta['unit']}: allowed range is {lo} to {hi} {meta['unit']}")

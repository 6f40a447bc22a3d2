"""Behaviour the README and SENSOR.md document, measured from the outside: the multiplexer's memory and charge
injection (by switching order), the TDC, TAC and electrode bandwidths of D Table 4-1 (step and frequency
responses), the front end's filter orders and corners, the PAC scale, the impact impulse m·v·(1 + e) and the
ringing amplitude it predicts, the displacement path, each noise source against the noise budget, the ADC's
rounding, clipping and input noise, and the published electrode table.

Each test states the documented figure it checks; the mutation catalogue (bench/verification/mutants.py) breaks
each of these on purpose and expects a test here to fail.
"""

import numpy as np
import pytest

from emulator import conversions as conv
from emulator.adc import Adc
from emulator.channels import channel_index
from emulator.electrodes import electrode_positions_mm
from emulator.noise_budget import budget
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.stimuli import (DROP_HEIGHT_M, GRAVITY_M_PER_S2, SPHERES, AmbientStep, Press, PressureCalibrator,
                              SphereDrop, Touch, Vibration)
from emulator.thermal import TAC_BIAS_V, ThermalModel

pytestmark = pytest.mark.unit
QUIET = NoiseSources.none()
LSB = conv.ADC_LSB_V


def amplitude_at(t, x, f_hz):
    """Least-squares amplitude of the sinusoid at ``f_hz`` in ``x`` (mean removed)."""
    w = 2 * np.pi * f_hz * np.asarray(t)
    basis = np.column_stack([np.sin(w), np.cos(w), np.ones_like(w)])
    (a, b, _), *_ = np.linalg.lstsq(basis, np.asarray(x, float), rcond=None)
    return float(np.hypot(a, b))


# --- the multiplexer (README "Electrodes"; emulator/electrodes.py) ------------------------------------------
def _settled_reads(first, then, n_first=6):
    """Analog value of ``then`` read right after ``n_first`` reads of ``first`` (100 µs apart), E17 pressed."""
    touch = Touch(0.1, 3.0, 0.2, 1.0, electrode="E17", indenter_radius_mm=3.0)
    s = Sensor(stimuli=[touch], channels_read=["E1", "E17"], noise=QUIET)
    chans = [channel_index(first)] * n_first + [channel_index(then)]
    t = 0.6 + np.arange(len(chans)) * 1e-4
    v = s.analog(chans, t)
    return v[-1], v[-2], s.adc.convert(v)[-1]


def test_the_multiplexer_keeps_0_67_percent_of_the_previous_electrode():
    """The hold node keeps exp(−20 µs / 4 µs) = 0.67 % of the previous electrode's value.  Measured by switching
    order only: E1 read after E17 (pressed: a much lower voltage) against E1 read after E1; the injected charge
    is the same either way and cancels."""
    e1_after_e1, _, code_same = _settled_reads("E1", "E1")
    e1_after_e17, e17_after_e17, code_switched = _settled_reads("E17", "E1")
    swing = e17_after_e17 - e1_after_e1
    assert swing < -0.5  # E17 is pressed hard: over half a volt below E1
    kept = (e1_after_e17 - e1_after_e1) / swing
    assert kept == pytest.approx(0.0067, rel=0.02)
    # and the host sees it in the codes: E1 reads lower after E17 by 0.67 % of the swing
    assert int(code_same) - int(code_switched) == pytest.approx(-0.0067 * swing / LSB, abs=1.0)
    assert int(code_same) - int(code_switched) >= 5


def test_charge_injection_offsets_repeated_reads_of_one_electrode():
    """Each switch injects charge (mux_injection_V) of which the node keeps the same 0.67 %: reading one electrode
    over and over settles a·q/(1 − a) ≈ 0.34 mV above the value D eq. 4.1 gives for its impedance."""
    p = SensorParams()
    s = Sensor(channels_read=["E5"], noise=QUIET)
    v = s.analog(np.full(20, channel_index("E5")), 0.1 + np.arange(20) * 1e-4)
    z_rest = p.electrode_series_ohm + p.fluid_sheet_ohm_mm / p.resting_gap_mm
    eq_4_1 = 3.3 * p.electrode_load_ohm / (z_rest + p.electrode_load_ohm)
    a = np.exp(-p.mux_acquisition_s / p.mux_settling_s)
    assert v[-1] - eq_4_1 == pytest.approx(a * p.mux_injection_V / (1 - a), rel=0.02)
    assert v[-1] - eq_4_1 == pytest.approx(0.34e-3, rel=0.05)


# --- TDC, TAC and electrode bandwidths (D Table 4-1) -------------------------------------------------------------
@pytest.fixture
def thermistor_drive(monkeypatch):
    """Replace the divider voltage that feeds the TDC read-out by ``volts_at(t)``, so the read-out's filters
    (22.6 Hz low-pass -> TDC; 0.45 Hz high-pass × 98 -> TAC) can be driven with steps and sines."""
    holder = {}
    advance = ThermalModel._advance_chunk

    def advance_noting_k(self):
        self._drive_k0 = self.k
        advance(self)

    def drive(self, xs):
        if not hasattr(self, "_drive_k0"):  # the initial state (t = 0)
            return np.asarray(holder["volts_at"](np.zeros(len(xs))), float)
        t = (self._drive_k0 + 1 + np.arange(len(xs))) * self.dt
        return np.asarray(holder["volts_at"](t), float)

    monkeypatch.setattr(ThermalModel, "_advance_chunk", advance_noting_k)
    monkeypatch.setattr(ThermalModel, "_tdc_from_state", drive)

    def sensor(volts_at):
        holder["volts_at"] = volts_at
        # an ambient step far in the future makes the sensor build its thermal network (no steady-state shortcut)
        return Sensor(stimuli=[AmbientStep(1e6, 25.0)], channels_read=["TDC", "TAC"], noise=QUIET)

    return sensor


def test_TDC_bandwidth_is_22_6_Hz(thermistor_drive):
    """Table 4-1: TDC 0–22.6 Hz.  A sine at 22.6 Hz comes through at −3 dB, 5 Hz nearly whole, 40 Hz well
    attenuated; a step settles within 30 ms but not at once."""
    tdc = channel_index("TDC")
    gains = {}
    for f in (5.0, 22.6, 40.0):
        s = thermistor_drive(lambda t, f=f: 1.0 + 0.01 * np.sin(2 * np.pi * f * t))
        t = np.arange(100, 400) * 0.01  # the network's own instants (100 Hz), after 1 s
        gains[f] = amplitude_at(t, s.analog(np.full(t.size, tdc), t), f) / 0.01
    assert gains[22.6] == pytest.approx(1 / np.sqrt(2), abs=0.04)
    assert gains[5.0] > 0.97 and gains[40.0] < 0.55
    s = thermistor_drive(lambda t: 1.0 + 0.01 * (t >= 1.0 - 1e-9))
    t = 1.0 + np.arange(-2, 10) * 0.01
    y = (s.analog(np.full(t.size, tdc), t) - 1.0) / 0.01
    assert abs(y[0]) < 1e-9 and abs(y[1]) < 1e-9  # nothing before the step
    assert 0.2 < y[2] < 0.8  # partway at the first instant of the step
    assert np.all(np.abs(y[5:] - 1.0) < 0.01)  # settled within 30 ms (a 22.6 Hz pole: τ = 7 ms)


def test_TAC_is_98_times_a_0_45_Hz_high_pass_of_TDC(thermistor_drive):
    """Table 4-1 and README: TAC = 1.65 V + 98 × HP(TDC), first-order high-pass at 0.45 Hz (τ = 0.354 s): a small
    TDC step makes TAC jump by 98 × the step and decay with τ."""
    s = thermistor_drive(lambda t: 1.0 + 0.005 * (t >= 1.0 - 1e-9))
    t = 1.0 + np.arange(5, 150) * 0.01
    tac = s.analog(np.full(t.size, channel_index("TAC")), t) - TAC_BIAS_V
    slope, intercept = np.polyfit(t - 1.0, np.log(tac), 1)
    assert -1 / slope == pytest.approx(1 / (2 * np.pi * 0.45), rel=0.05)
    assert np.exp(intercept) == pytest.approx(98 * 0.005, rel=0.05)


def test_electrode_bandwidth_is_100_Hz():
    """Table 4-1: electrodes 0–100 Hz.  A contact that arrives at once (reference profile: electrodes at 2 kHz)
    moves the pressed electrode with a single 100 Hz pole: the remaining step decays with τ = 1/(2π·100 Hz)."""
    touch = Touch(0.3 - 1e-6, 2.0, 1e-7, 1.0, electrode="E17", indenter_radius_mm=3.0)
    s = Sensor(stimuli=[touch], channels_read=["E17"], fidelity="reference", noise=QUIET)
    t = np.concatenate([np.arange(0.2, 0.3, 5e-4), 0.3 + np.arange(0, 41) * 2.5e-4, [0.4]])
    v = s.analog(np.full(t.size, channel_index("E17")), t)
    final, before = v[-1], v[0]
    assert final < before - 0.3  # the pressed electrode's voltage falls
    sel = (t > 0.3005) & (t < 0.306)
    rest = (v[sel] - final) / (before - final)
    assert np.all(rest > 0)
    slope, _ = np.polyfit(t[sel], np.log(rest), 1)
    assert -1 / slope == pytest.approx(1 / (2 * np.pi * 100.0), rel=0.15)


# --- front end: filter orders and corners, scale (SENSOR.md §3) --------------------------------------------------
def _node_amplitude(channel, f_hz, amplitude_Pa, fidelity, rate_Hz, duration_s):
    cal = PressureCalibrator(0.0, duration_s + 0.1, amplitude_Pa=amplitude_Pa, frequency_Hz=f_hz, fade_s=0.0)
    s = Sensor(stimuli=[cal], channels_read=[channel], fidelity=fidelity, noise=QUIET)
    t = np.arange(int(round(0.05 * rate_Hz)), int(round(duration_s * rate_Hz))) / rate_Hz
    return amplitude_at(t, s.analog(np.full(t.size, channel_index(channel)), t), f_hz)


def test_pdc_front_end_is_a_2nd_order_butterworth_at_1040_Hz():
    """Stage 1: gain 10 with a 2nd-order Butterworth low-pass at 1040 Hz: |H| = 1/√(1 + (f/1040)⁴) — −3 dB at the
    corner and 0.243 an octave above (a first-order filter would give 0.447)."""
    p = SensorParams()
    for f in (100.0, 1040.0, 2080.0):
        volts = _node_amplitude("PDC", f, 1000.0, "reference", 70400.0, 0.08)
        gain = volts / (1000.0 * p.pdc_V_per_Pa)
        assert gain == pytest.approx(1 / np.sqrt(1 + (f / 1040.0) ** 4), rel=0.03), f


def test_pac_band_starts_with_a_1st_order_10_Hz_high_pass():
    """Stage 2: 10 Hz first-order high-pass: |H| = 1/√(1 + (10/f)²) — −3 dB at 10 Hz, 0.447 at 5 Hz."""
    p = SensorParams()
    for f in (5.0, 10.0, 40.0):
        volts = _node_amplitude("PAC", f, 200.0, "default", 1000.0, 2.0)
        gain = volts / (200.0 * p.pac_V_per_Pa)
        assert gain == pytest.approx(1 / np.sqrt(1 + (10.0 / f) ** 2), rel=0.03), f


def test_pac_scale_is_0_37_Pa_per_bit():
    """0.218 mV/V·kPa × 10 V × 10 × 99.1 over a 3.3 V / 4096 LSB: 0.37 Pa per PAC bit (D Table 4-1), in the band."""
    bits = _node_amplitude("PAC", 200.0, 300.0, "default", 2200.0, 1.0) / LSB
    assert 300.0 / bits == pytest.approx(0.37, rel=0.02)


def test_a_1_N_press_raises_PDC_by_87_bits():
    """11.5 mN per PDC bit below the knee (D ch. 4), on a press loading at D's ~0.5 N/s: 1 N raises PDC by
    1/0.0115 = 87 bits (± 5 %, the claim's tolerance). Held, the skin keeps creeping: the relaxed rise is larger
    by no more than the creep the force claims bound (15 %)."""
    s = Sensor(stimuli=[Press(0.1, 2.0, ramp_s=4.0, hold_s=0.2)], channels_read=["PDC"], noise=QUIET)
    v = s.analog([1, 1], [0.05, 2.1])  # 1 N on the loading ramp
    assert (v[1] - v[0]) / LSB == pytest.approx(1 / 0.0115, rel=0.05)
    held = Sensor(stimuli=[Press(0.1, 1.0, 0.2, 8.0)], channels_read=["PDC"], noise=QUIET)
    w = held.analog([1, 1], [0.05, 8.0])
    assert 1.0 < (w[1] - w[0]) / (v[1] - v[0]) < 1.15



def test_the_published_pdc_force_conversion_reads_a_1_N_press_as_1_N():
    """SENSOR.md §1: 11.5 mN per PDC bit below 2 N.  The host's conversion (conversions.pdc_to_force_n, the
    figures' PDC_force_N column) is that slope, and applied to the codes of a 1 N press on D's ~0.5 N/s loading ramp
    it reads 1 N within the claim's 5 %."""
    assert float(conv.pdc_to_force_n(1000 + 87, 1000)) == pytest.approx(87 * 0.0115, rel=1e-12)
    s = Sensor(stimuli=[Press(0.1, 2.0, ramp_s=4.0, hold_s=0.2)], channels_read=["PDC"], noise=QUIET)
    codes = s.analog([1, 1], [0.05, 2.1]) / LSB  # rest, then 1 N on the loading ramp
    assert float(conv.pdc_to_force_n(codes[1], codes[0])) == pytest.approx(1.0, rel=0.05)

# --- impacts (SENSOR.md §1 and §7) --------------------------------------------------------------------------------
def test_the_impact_impulse_is_m_v_1_plus_e():
    """A sphere dropped from 7 cm falls through air and hits just under √(2gh) (the 1 mm steel bearing 0.6 %
    under), bounces with restitution e and transfers m·v·(1 + e) at that speed v.  A scene's drops take e from the
    sensor's ``impact_restitution`` parameter."""
    m = SPHERES["1 mm steel bearing"][0]
    v = SphereDrop(0.1, m).impact_speed_m_per_s
    assert np.sqrt(2 * 9.80665 * 0.07) == pytest.approx(1.17172, rel=1e-5)
    assert GRAVITY_M_PER_S2 == 9.80665 and DROP_HEIGHT_M == 0.07
    assert 0.99 * 1.17172 < v < 0.997 * 1.17172
    for e in (0.0, 0.3, 0.8):
        drop = SphereDrop(0.1, m, restitution=e)
        assert drop.impulse_Ns == pytest.approx(m * v * (1 + e), rel=1e-9)
        assert float(drop.cumulative(np.array([1.0]))[0]) == pytest.approx(m * v * (1 + e), rel=1e-9)
    from bench.scenes.scene import parse_scene

    sc = parse_scene({"scene": {"name": "t", "duration_s": 1.0}, "sensor": {"impact_restitution": 0.6},
                      "stimulus": [{"kind": "sphere_drop", "sphere": "1 mm steel bearing", "at_s": 0.5}]})
    assert sc.stimuli[0].restitution == 0.6
    assert sc.stimuli[0].impulse_Ns == pytest.approx(m * v * 1.6, rel=1e-9)
    # and the pressure the host sees scales with (1 + e)
    t = np.arange(0, 0.3, 1 / 22000.0)
    peaks = []
    for e in (0.0, 0.6):
        s = Sensor(stimuli=[SphereDrop(0.1, m, restitution=e)], channels_read=["PAC"], noise=QUIET)
        x = s.analog_trace("PAC", t)
        peaks.append(np.max(np.abs(x - x[0])))
    assert peaks[1] / peaks[0] == pytest.approx(1.6, rel=0.01)


def _ring(mass_kg, **drop):
    """Noise-free analog PAC after a sphere lands at 0.1 s, fitted as A·e^(−t/τ)·sin(2πft + φ) from 2 ms on."""
    from bench.verification.analysis import fit_decaying_sinusoid

    s = Sensor(stimuli=[SphereDrop(0.1, mass_kg, **drop)], channels_read=["PAC"], noise=QUIET)
    t = np.arange(0.0, 0.25, 1 / 22000.0)
    x = s.analog_trace("PAC", t)
    sel = t > 0.102
    return fit_decaying_sinusoid(t[sel] - 0.1, x[sel] - x[0])


def test_an_impact_rings_at_330_Hz_with_a_20_ms_decay():
    """D ch. 5: impacts produce decaying sinusoids at about 330 Hz with a 20 ms time constant."""
    ring = _ring(SPHERES["1 mm steel bearing"][0])
    assert ring.frequency_Hz == pytest.approx(330.0, rel=0.02)
    assert ring.decay_s == pytest.approx(0.020, rel=0.05)


def test_an_impact_rings_with_the_amplitude_its_impulse_predicts():
    """The ring's amplitude follows from the impulse J = m·v·(1 + e): the Hertz force pulse f(t) (area J) into the
    skin's instantaneous force -> pressure slope (creep has no time to act) and the unit-DC-gain resonance (impulse
    response ω0²/ωd·e^(−σt)·sin ωd t), so the amplitude is ω0²/ωd·|∫ f(τ)·e^((σ − iωd)τ) dτ|, then the bridge,
    both gains and the front end's filters at the ring frequency."""
    from emulator.mechanics import skin_fluid

    p = SensorParams()
    m = SPHERES["1 mm steel bearing"][0]
    drop = SphereDrop(0.1, m)
    ring = _ring(m)
    fluid = skin_fluid(p)
    w0, sigma = 2 * np.pi * fluid.resonance_Hz, 1 / fluid.decay_s
    wd = np.sqrt(w0**2 - sigma**2)
    tau = np.linspace(0.0, drop.contact_duration_s, 20001)
    force = np.gradient(drop.cumulative(0.1 + tau), tau)
    weighted = abs(np.trapezoid(force * np.exp((sigma - 1j * wd) * tau), tau))
    f = wd / (2 * np.pi)
    front_end = 1 / np.sqrt(1 + (f / 1040.0) ** 4) / np.sqrt(1 + (10.0 / f) ** 2)
    predicted = fluid.pressure_per_N_instant * w0**2 / wd * weighted * p.pac_V_per_Pa * front_end
    assert drop.impulse_Ns == pytest.approx(m * drop.impact_speed_m_per_s * 1.3, rel=1e-9)
    assert np.trapezoid(force, tau) == pytest.approx(drop.impulse_Ns, rel=1e-3)
    assert abs(ring.amplitude) == pytest.approx(predicted, rel=0.05)


# --- the displacement path (README "Fluid and skin") -------------------------------------------------------------
def test_skin_displacement_reaches_the_liquid_with_the_documented_gain_and_zero():
    """Skin displacement -> pressure: a static gain of the liquid displaced over the loaded area, A·dP/dV
    (3.2 Pa/µm at 0.5 mL), through the 330 Hz / 20 ms resonance plus a direct path (a real zero at 500 Hz).
    Reference profile: the default one's discretization is 5 % low at 900 Hz (its documented price, see the
    benchmark)."""
    p = SensorParams()
    gain_Pa_per_m = p.skin_load_area_m2 * 12e3 * 1.5 * 0.5 ** 0.5 * 1e6  # A·dP/dV of P = 12 kPa/mL · V^1.5
    w0, sigma = 2 * np.pi * 330.0, 1 / 0.020
    for f in (20.0, 330.0, 900.0):
        vib = Vibration(0.0, 0.5, 1e-6, f, fade_s=0.0)
        s = Sensor(stimuli=[vib], channels_read=["PDC"], fidelity="reference", noise=QUIET)
        t = np.arange(int(0.2 * 8800), int(0.45 * 8800)) / 8800.0
        pa = amplitude_at(t, s.analog(np.ones(t.size, int), t), f) / p.pdc_V_per_Pa
        s_ = 2j * np.pi * f
        h = (1 + s_ / (2 * np.pi * 500.0)) * w0**2 / (s_**2 + 2 * sigma * s_ + w0**2)
        h *= 1 / np.sqrt(1 + (f / 1040.0) ** 4)  # the PDC node's anti-alias filter
        assert pa / 1e-6 == pytest.approx(gain_Pa_per_m * abs(h), rel=0.03), f


# --- noise sources against the budget (D Table 5-1; `biotac-bench noise-budget`) ----------------------------------
def _pac_std_bits(noise, seconds=4.0):
    s = Sensor(channels_read=["PAC"], seed=21, noise=noise)
    t = np.arange(int(seconds * 4400)) / 4400.0
    x = s.analog_trace("PAC", t)
    return float(np.std(x[t > 0.1])) / LSB


def test_each_noise_source_matches_the_budget():
    """The noise each source puts on PAC, measured with only that source on, matches the noise budget's line
    (computed from the parameters and the filters' noise bandwidth, independently of the noise generators)."""
    lines = {x.source: x.pac_bits for x in budget()}
    off = dict(johnson=False, amplifier=False, mains_hum=False, adc=False, spi_coupling=False, thermistor=False)
    johnson = _pac_std_bits(NoiseSources(**{**off, "johnson": True}))
    amplifier = _pac_std_bits(NoiseSources(**{**off, "amplifier": True}))
    assert johnson == pytest.approx(lines["bridge Johnson noise"], rel=0.05)
    assert amplifier == pytest.approx(np.hypot(lines["amplifier voltage noise"], lines["amplifier current noise × R"]),
                                      rel=0.05)
    assert lines["intrinsic total (Table 5-1)"] == pytest.approx(0.6, rel=0.1)


def test_the_hum_fills_the_largest_2_Hz_band_with_0_2_bits2():
    """The hum is sized so that the largest 2 Hz band of a 1 s PAC spectrum at rest holds 0.2 bits² (D ch. 5):
    a 60 Hz line of 0.2 bits² power (amplitude √0.4 bits) on PAC."""
    off = dict(johnson=False, amplifier=False, adc=False, spi_coupling=False, thermistor=False)
    s = Sensor(channels_read=["PAC"], seed=3, noise=NoiseSources(**off, mains_hum=True))
    t = np.arange(2200, 4400) / 2200.0
    bits = amplitude_at(t, s.analog_trace("PAC", t), 60.0) / LSB
    assert bits**2 / 2 == pytest.approx(0.2, rel=0.05)


# --- the ADC (README "ADC") ---------------------------------------------------------------------------------------
def test_adc_rounds_to_the_nearest_code_and_clips_at_the_rails():
    """12 bits over 0–3.3 V: code = round(V / (3.3 V / 4096)), limited to 0..4095."""
    adc = Adc(SensorParams(), seed=0, noise=False, spi_coupling=False)
    lsb = 3.3 / 4096
    k = np.array([0, 1, 1000, 2048, 4000, 4094])
    assert np.array_equal(adc.convert(k * lsb + 0.4 * lsb), k)
    assert np.array_equal(adc.convert(k * lsb + 0.6 * lsb), k + 1)
    assert np.array_equal(adc.convert(np.array([-0.2, 3.2996, 3.3, 3.6, 5.0])), [0, 4095, 4095, 4095, 4095])


# --- electrode geometry (SENSOR.md §5; G = Ruppel et al. 2018) ----------------------------------------------------
PUBLISHED_ELECTRODES_MM = np.array([  # electrodes.csv of the shared spec, E1..E19: x, y, z
    [0.993, -4.855, -1.116], [-2.700, -3.513, -3.670], [-6.200, -3.513, -3.670], [-8.000, -4.956, -1.116],
    [-10.500, -3.513, -3.670], [-13.400, -4.956, -1.116], [4.763, 0.000, -2.330], [3.031, -1.950, -3.330],
    [3.031, 1.950, -3.330], [1.299, 0.000, -4.330], [0.993, 4.855, -1.116], [-2.700, 3.513, -3.670],
    [-6.200, 3.513, -3.670], [-8.000, 4.956, -1.116], [-10.500, 3.513, -3.670], [-13.400, 4.956, -1.116],
    [-2.800, 0.000, -5.080], [-9.800, 0.000, -5.080], [-13.600, 0.000, -5.080]])


def test_electrode_positions_are_the_published_table():
    """fixtures/electrodes.csv holds G's 19 coordinates; the set is mirror-symmetric about y = 0 (E1..E6 mirror
    E11..E16, E8 mirrors E9); and the electrodes along the finger's body sit on the 5 mm core the contact
    geometry assumes (they lie within 5.1 mm of its axis)."""
    from emulator.electrodes import CORE_RADIUS_MM, surface_point_over_mm

    pos = electrode_positions_mm()
    np.testing.assert_allclose(pos, PUBLISHED_ELECTRODES_MM, atol=1e-9)
    mirrored = pos * np.array([1, -1, 1])
    for a, b in [(n, n + 10) for n in range(0, 6)] + [(7, 8)]:
        np.testing.assert_allclose(mirrored[a], pos[b], atol=1e-9)
    radial = np.hypot(pos[:, 1], pos[:, 2])
    assert np.all(radial <= CORE_RADIUS_MM + 0.1)
    assert radial[[16, 17, 18]] == pytest.approx(5.08, abs=1e-9)
    # a contact "over E17" lands on the core surface right over it
    centre = surface_point_over_mm(pos[16])
    assert np.linalg.norm(centre - pos[16]) < 0.1

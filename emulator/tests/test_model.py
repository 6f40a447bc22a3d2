"""The physics stages and the effect graph: demand-driven construction, independent random streams."""

import numpy as np
import pytest

from emulator.channels import DEFAULT_FRAME_NAMES
from emulator import conversions as conv
from emulator.conversions import ADC_LSB_V
from emulator.mechanics import static_pressure_from_force
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.stimuli import SPHERES, Press, PressureCalibrator, SphereDrop, Tap, Vibration

pytestmark = pytest.mark.unit


def effects(sensor):
    return [e["name"] for e in sensor.effects_report()]


def test_only_the_effects_the_scene_needs_are_built():
    rest_pdc = Sensor(channels_read=["PDC"])
    assert "stage2" not in effects(rest_pdc)  # nobody reads PAC
    assert "force_coupling" not in effects(rest_pdc)  # no force stimulus
    assert "vibration_coupling" not in effects(rest_pdc)
    taps = Sensor(stimuli=[Tap(0.1, 1.0)], channels_read=["PAC"])
    assert {"contact_force", "force_coupling", "stage2"} <= set(effects(taps))
    assert "skin_displacement" not in effects(taps)
    electrodes_only = Sensor(channels_read=["E1", "TDC"])
    assert effects(electrodes_only) == ["thermal_steady_state", "electrodes"]  # no grid physics at all
    quiet = Sensor(channels_read=["PAC"], noise=NoiseSources.none())
    assert not {"bridge_johnson_noise", "amplifier_noise", "mains_hum"} & set(effects(quiet))


def test_reference_profile_adds_second_order_effects():
    ref = Sensor(channels_read=["PAC"], fidelity="reference")
    assert "stage2_noise" in effects(ref)
    assert ref.graph.effects[[e.name for e in ref.graph.effects].index("bridge")].duct is not None



@pytest.mark.parametrize("name", ["fast", "default", "reference"])
def test_each_fidelity_profile_is_what_its_description_says(name):
    """A profile's description (printed by scripts/benchmark, read by whoever picks one) states its grid, electrode
    rate, texture resolution, friction substeps and patch radii: the fields are those numbers.  The electrode rate
    stays above twice the channels' 100 Hz bandwidth (emulator/electrodes.py: 250 Hz to 2 kHz)."""
    import re

    from emulator.fidelity import profile

    f = profile(name)
    d = f.description
    num = lambda pattern: float(re.search(pattern, d).group(1))  # noqa: E731
    assert f.grid_Hz == pytest.approx(1e3 * num(r"([\d.]+) kHz grid"))
    rate = re.search(r"electrodes at ([\d.]+) (k?)Hz", d)
    assert f.electrode_rate_Hz == pytest.approx(float(rate.group(1)) * (1e3 if rate.group(2) else 1.0))
    assert f.sliding_dx_m == pytest.approx(1e-6 * num(r"textures at ([\d.]+) µm"))
    assert f.friction_substeps == (int(num(r"friction oversampled ×(\d+)")) if "oversampled" in d else 1)
    assert "friction on the grid" in d or f.friction_substeps > 1
    assert f.patch_radii == int(num(r"(\d+) patch radii"))
    assert f.electrode_rate_Hz > 2 * SensorParams().electrode_bandwidth_Hz

def test_adc_noise_stream_is_independent_of_the_grid_noise():
    t = np.arange(2200) / 2200.0
    a = Sensor(channels_read=["PAC"], seed=9, noise=NoiseSources(johnson=False, amplifier=False, mains_hum=False))
    b = Sensor(channels_read=["PAC"], seed=9, noise=NoiseSources(mains_hum=False, johnson=False,
                                                                 amplifier=False, spi_coupling=False))
    assert np.array_equal(a.sample(np.zeros(2200, int), t), b.sample(np.zeros(2200, int), t))


def test_force_curve_is_linear_below_the_knee_and_flattens_above():
    p = SensorParams()
    f = np.linspace(0, 1.5, 50)  # well below the 2 N knee (the knee is smooth over ~0.1 N)
    slope = np.gradient(static_pressure_from_force(f, p), f)
    assert np.allclose(slope, p.force_to_pressure_Pa_per_N, rtol=0.02)
    above = np.gradient(static_pressure_from_force(np.linspace(2.5, 5, 20), p), np.linspace(2.5, 5, 20))
    assert np.all(above < 0.3 * p.force_to_pressure_Pa_per_N)
    assert static_pressure_from_force(-1.0, p) == 0.0


@pytest.mark.parametrize("width_N", [0.08, 1.0, 2.0])  # the default, and the knee width's range up to its top
def test_the_force_curve_starts_from_zero_at_first_touch_for_any_knee_width(width_N):
    """P(F) = k·(F − (1 − r)·w·(softplus((F − F_knee)/w) − softplus(−F_knee/w))) (mechanics.static_pressure_from_force):
    the second softplus makes P(0) = 0, so a touch of 1 µN raises the pressure by k·1 µN at most (Pa), whatever the
    knee's width w (N); below the knee the curve is then k·F less a smooth share that grows from zero.  (A mutation
    hunt: without it the curve jumped by ~0.5·k·1 N at first touch for a 2 N wide knee, which the default 0.08 N
    width hides to 1e-11.)"""
    p = SensorParams().replace(force_knee_width_N=width_N)
    k = p.force_to_pressure_Pa_per_N
    touch = static_pressure_from_force(1e-6, p)
    assert 0.0 <= touch <= k * 1e-6
    f = np.array([0.1, 0.5, 1.0])
    assert np.all(static_pressure_from_force(f, p) <= k * f)


def test_inflation_raises_resting_pressure_and_moves_the_resonance_within_200_to_350_Hz():
    vols = [0.2, 0.4, 0.6, 0.8, 1.0]
    pressures = [SensorParams(inflation_volume_mL=v).resting_pressure_Pa for v in vols]
    assert np.all(np.diff(pressures) > 0)
    freqs = [SensorParams(inflation_volume_mL=v).resonance_at_inflation_Hz for v in vols]
    assert np.all(np.diff(freqs) >= 0) and min(freqs) >= 200 and max(freqs) <= 350


def test_hotter_bridge_drifts_offset_and_span():
    cold, hot = SensorParams(ambient_temperature_C=15.0), SensorParams(ambient_temperature_C=35.0)  # core 25 vs 45 °C
    assert hot.bridge_span_V_per_Pa < cold.bridge_span_V_per_Pa
    assert hot.bridge_offset_V != cold.bridge_offset_V
    t = np.arange(100) / 100.0
    hot_pdc = Sensor(hot, channels_read=["PDC"], noise=NoiseSources.none()).analog(np.ones(100, int), t)
    cold_pdc = Sensor(cold, channels_read=["PDC"], noise=NoiseSources.none()).analog(np.ones(100, int), t)
    # 20 K apart: offset −1 µV/V/K and span −0.2 %/K (the drift parameters) on 10 V, times the gain of 10
    p = SensorParams()
    offset_V = 10.0 * -1e-6 * 20.0
    span_V = 10.0 * 0.218e-6 * p.resting_pressure_Pa * (-2e-3 * 20.0)
    assert np.ptp(hot_pdc) == 0 and np.ptp(cold_pdc) == 0  # settled: no drift in time
    assert hot_pdc[0] - cold_pdc[0] == pytest.approx(10.0 * (offset_V + span_V), rel=0.01)


def test_johnson_noise_follows_sqrt_4kTR():
    p = SensorParams()
    assert p.johnson_noise_V_per_rtHz * np.sqrt(1040) == pytest.approx(0.29e-6, rel=0.05)


def test_sphere_impulse_and_energy_follow_the_drop_height():
    s = SphereDrop(0.0, 0.422e-6, 0.07, restitution=0.0, air_density_kg_per_m3=0.0)
    assert s.energy_J == pytest.approx(0.289e-6, rel=0.01)  # D Table 5-2
    assert s.impulse_Ns == pytest.approx(0.422e-6 * np.sqrt(2 * 9.80665 * 0.07))
    assert SphereDrop(0.0, 0.422e-6, 0.07, restitution=0.0).impulse_Ns < s.impulse_Ns  # the air slows it


def test_force_pulses_deliver_the_same_impulse_on_any_grid():
    drop = SphereDrop(0.01, 1e-6)
    for fs in (4400.0, 8800.0, 70400.0):
        dt = 1 / fs
        t = np.arange(int(0.02 * fs)) * dt
        mean_force = (drop.cumulative(t + dt / 2) - drop.cumulative(t - dt / 2)) / dt
        assert mean_force.sum() * dt == pytest.approx(drop.impulse_Ns, rel=1e-9)


def test_press_and_tap_cumulatives_integrate_their_force():
    for s in (Press(0.1, 2.0, 0.3, 0.5), Tap(0.1, 1.5, 0.04)):
        t = np.linspace(0, 2, 200001)
        f = s.force(t)
        assert np.trapezoid(f, t) == pytest.approx(float(s.cumulative(np.array([2.0]))[0]), rel=1e-4)


def test_vibration_sweep_covers_its_frequency_range():
    v = Vibration(0.0, 1.0, 1e-6, 10.0, 900.0)
    assert v.frequency_at(0.0) == pytest.approx(10.0)
    assert v.frequency_at(1.0) == pytest.approx(900.0)
    assert np.max(np.abs(v.value(np.linspace(0, 1, 10000)))) <= 1e-6 + 1e-15


def test_calibrator_pressure_reaches_pdc_at_the_published_scale():
    cal = PressureCalibrator(0.1, 1.0, offset_Pa=10e3, fade_s=0.0)
    s = Sensor(stimuli=[cal], channels_read=["PDC"], noise=NoiseSources.none())
    t = np.array([0.05, 0.8])
    v = s.analog(np.ones(2, int), t)
    assert (v[1] - v[0]) / ADC_LSB_V * 0.0365 == pytest.approx(10.0, rel=0.02)


def test_unknown_channel_and_undeclared_channel_are_refused():
    with pytest.raises(ValueError, match="unknown channel"):
        Sensor(channels_read=["PXX"])
    s = Sensor(channels_read=["PAC"])
    with pytest.raises(ValueError, match="not declared"):
        s.analog([1], [0.0])


def test_instants_older_than_the_history_are_refused_clearly():
    s = Sensor(channels_read=["PAC"], block_s=0.01)
    s.analog([0], [5.0])
    with pytest.raises(ValueError, match="older than the retained history"):
        s.analog([0], [1.0])


def test_full_frame_channels_all_convert():
    """Every channel of the default frame converts to its resting value, read back with the published
    conversions: PAC and TAC at mid-scale, PDC at the resting pressure, TDC about 10 °C above ambient, every
    electrode at the impedance of the resting fluid layer."""
    p = SensorParams()
    s = Sensor(channels_read=DEFAULT_FRAME_NAMES, seed=2, noise=NoiseSources.none())
    from emulator.channels import channel_index
    chans = [channel_index(n) for n in DEFAULT_FRAME_NAMES]
    codes = s.sample(chans, np.arange(44) / 4400.0)
    by = dict(zip(DEFAULT_FRAME_NAMES, codes.astype(float)))
    assert codes.dtype == np.uint16
    assert by["PAC"] == 2048 and by["TAC"] == 2048
    pdc_offset = p.stage1_bias_V / ADC_LSB_V  # zero gauge pressure
    assert float(conv.pdc_to_kpa(by["PDC"], pdc_offset)) == pytest.approx(p.resting_pressure_Pa / 1e3, rel=0.02)
    assert float(conv.tdc_to_celsius(by["TDC"])) == pytest.approx(p.ambient_temperature_C + 10.0, abs=1.0)
    z_rest = p.electrode_series_ohm + p.fluid_sheet_ohm_mm / p.resting_gap_mm
    electrodes = [by[f"E{n}"] for n in range(1, 20)]
    assert conv.impedance_ohm(np.array(electrodes)) == pytest.approx(np.full(19, z_rest), rel=0.01)


def test_analog_trace_does_not_depend_on_how_the_instants_are_chunked():
    t = np.arange(0, 3.0, 1 / 2200.0)
    stimuli = [Tap(0.7, 1.0), SphereDrop(2.1, SPHERES["1 mm steel bearing"][0])]
    whole = Sensor(stimuli=stimuli, channels_read=["PAC", "PDC"], seed=5).analog_trace("PAC", t, chunk_s=10.0)
    pieces = Sensor(stimuli=stimuli, channels_read=["PAC", "PDC"], seed=5).analog_trace("PAC", t, chunk_s=0.137)
    assert whole.shape == t.shape and np.all(np.isfinite(whole))
    np.testing.assert_array_equal(whole, pieces)


def test_each_batch_is_read_by_its_own_channels_whatever_the_batch_before():
    """analog() keeps the last batch's channel plan: batches of the same length with their channels in another
    order read what a sensor planning every batch afresh reads (the multiplexer's memory included), and an
    undeclared channel is still refused."""
    from emulator.channels import channel_index
    frame = np.array([channel_index(n) for n in DEFAULT_FRAME_NAMES])
    kept, fresh = (Sensor(channels_read=DEFAULT_FRAME_NAMES, seed=2) for _ in range(2))
    for k, channels in enumerate((frame, frame[::-1], frame[::-1], np.roll(frame, 5), frame)):
        times = (np.arange(44) + 44 * k) / 4400.0
        fresh._last_plan = None  # no plan kept: each batch planned from its own channels
        assert np.array_equal(kept.analog(channels, times), fresh.analog(channels, times)), k
    with pytest.raises(ValueError, match="not declared"):
        kept.analog(np.r_[frame[:43], 9], (np.arange(44) + 44 * 5) / 4400.0)


def test_a_batchs_channel_plan_is_shared_by_sensors_with_the_same_channel_map_only():
    """Plans are remembered across sensors (a rig builds one per trial): a second sensor reading the same channels
    gets the same (read-only) plan; a sensor whose grid nodes differ (PDC alone: node 0, not 1) gets its own, and
    reads PDC to the bit as the first does."""
    from emulator.channels import channel_index
    pdc = np.full(44, channel_index("PDC"))
    times = np.arange(44) / 4400.0
    both, again, alone = (Sensor(channels_read=names, seed=2) for names in (("PAC", "PDC"), ("PAC", "PDC"), ("PDC",)))
    plan = both._plan(pdc)
    assert again._plan(pdc) is plan and plan[0] == [(1, None)]
    assert alone._plan(pdc)[0] == [(0, None)]
    frame = np.array([channel_index(n) for n in DEFAULT_FRAME_NAMES])
    for _, at in Sensor(channels_read=DEFAULT_FRAME_NAMES, seed=2)._plan(frame)[0]:
        assert at is None or not at.flags.writeable
    np.testing.assert_array_equal(alone.analog(pdc, times), both.analog(pdc, times))


def test_the_compiled_interpolation_is_the_numpy_formula_to_the_bit():
    """(consistency) :func:`emulator.sensor._grid_positions` and :func:`_interpolate` (the sensor's reading between
    grid samples, compiled) give numpy's i = ⌊t·fs⌋, frac = t·fs − i and h[i]·(1 − frac) + h[i + 1]·frac to the bit,
    at every position or at chosen ones; instants that are negative, NaN or infinite are refused by name."""
    from emulator.sensor import _ALL, _grid_positions, _interpolate

    rng = np.random.default_rng(3)
    fs = 8800.0
    t = np.sort(rng.uniform(0.0, 2.0, 5000))
    h = rng.standard_normal(int(2.0 * fs) + 2)
    i, frac, i_min, i_max = _grid_positions(t, fs)
    x = t * fs
    expected_i = np.floor(x).astype(np.int64)
    np.testing.assert_array_equal(i, expected_i)
    np.testing.assert_array_equal(frac, x - expected_i)
    assert (i_min, i_max) == (expected_i.min(), expected_i.max())
    out = np.full(t.size, np.nan)
    _interpolate(h, i, frac, _ALL, out)
    np.testing.assert_array_equal(out, h[i] * (1.0 - frac) + h[i + 1] * frac)
    at = np.flatnonzero(rng.random(t.size) < 0.3)
    some = np.full(t.size, np.nan)
    _interpolate(h, i, frac, at, some)
    np.testing.assert_array_equal(some[at], out[at])
    assert np.isnan(np.delete(some, at)).all()
    s = Sensor(channels_read=["PAC"])
    for bad in (-1e-3, np.nan, np.inf):
        with pytest.raises(ValueError, match="finite and ≥ 0"):
            s.analog([0, 0], [0.1, bad])


def test_a_blocks_sample_times_start_at_its_first_grid_index():
    """Block(n0, n, fs).times are (n0 + i)/fs: an effect driven by time (the core temperature, a leak) meets the
    same instant at t = 0 in settle() and in the first processed sample."""
    from emulator import thermal
    from emulator.effects import Block
    from emulator.transducer import CoreTemperature

    fs = 4400.0
    assert np.array_equal(Block(0, 3, fs).times, np.array([0.0, 1.0, 2.0]) / fs)
    assert np.array_equal(Block(10, 2, fs).times, np.array([10.0, 11.0]) / fs)
    events = thermal.ThermalEvents([], power_on_s=0.0)  # warming from ambient: the temperature moves every step
    core = CoreTemperature(thermal.ThermalModel(SensorParams(), events, seed=0, noise=False))
    assert core.process(Block(0, 1, fs), {})["bridge_temperature_C"][0] == core.settle({})["bridge_temperature_C"]


@pytest.mark.parametrize("core_C", [25.0, 35.0, 45.0])
def test_the_bridge_settles_where_it_runs_whatever_the_core_temperature(core_C):
    """A bridge following the core temperature starts (settle) at the voltage its first processed sample has for the
    same pressure and temperature: a sensor powered on cold has no start-up transient on PDC or PAC."""
    from emulator.effects import Block
    from emulator.transducer import Bridge

    p = SensorParams()
    for duct, fs in ((False, 8800.0), (True, 88000.0)):  # the duct resonance (18.7 kHz) needs the finer grid
        bridge = Bridge(p, fs, duct, thermal=True)
        pressure = 4000.0
        start = bridge.settle({"fluid_pressure_Pa": pressure, "bridge_temperature_C": core_C})["stage1_input_V"]
        first = bridge.process(Block(0, 4, fs), {"fluid_pressure_Pa": np.full(4, pressure),
                                                 "bridge_temperature_C": np.full(4, core_C)})["stage1_input_V"]
        assert first == pytest.approx(np.full(4, start), rel=1e-12, abs=1e-15)
        assert start == pytest.approx(p.bridge_offset_at(core_C) + p.bridge_span_at(core_C) * pressure, rel=1e-12)


def test_a_sensor_started_between_grid_samples_can_be_read_at_its_start():
    # the start instant exists ("earlier instants do not exist"): read there, a sensor settled at rest reads what one
    # started at 0 reads at that instant.  0.07 s·8800 Hz is 616.0000000000001 in floating point and 1e-4 s lies
    # between grid samples; 1 % of an LSB allows for nothing but rounding (noise is off)
    for start in (0.07, 1e-4, 1.12):
        late = Sensor(channels_read=["PDC"], noise=NoiseSources.none(), start_s=start)
        early = Sensor(channels_read=["PDC"], noise=NoiseSources.none())
        assert late.analog([1], [start])[0] == pytest.approx(early.analog([1], [start])[0], abs=0.01 * ADC_LSB_V)
        with pytest.raises(ValueError, match=r"before the sensor's start .* earlier instants do not exist"):
            late.analog([1], [start - 1e-6])  # the grid sample kept before the start is not an instant of it


def test_a_tap_is_a_raised_cosine_pulse_peaking_at_its_middle():
    # raised cosine F = peak·(1 − cos(2π·x/T))/2: 0, peak/2, peak, peak/2, 0 at x = 0, T/4, T/2, 3T/4, T; 1 µN
    # covers the central difference (h = 1e-7 s) of the closed-form cumulative
    from emulator.stimuli import ForceStimulus

    tap = Tap(0.1, 1.5, 0.04)
    x = np.array([0.0, 0.25, 0.5, 0.75, 1.0]) * 0.04
    assert tap.force(0.1 + x) == pytest.approx([0.0, 0.75, 1.5, 0.75, 0.0], abs=1e-6)
    # the exact force a placed tap's electrodes feel is the derivative of the cumulative the fluid feels (the base
    # class's central difference)
    t = np.linspace(0.0, 0.2, 2001)
    assert tap.force(t) == pytest.approx(ForceStimulus.force(tap, t), abs=1e-6)


def test_a_press_lasts_both_ramps_and_a_touch_has_the_force_of_its_cumulative():
    from emulator.effects import Block
    from emulator.stimuli import ContactForce, Touch

    # ramp r up, hold h, ramp r down: the press lasts 2r + h and delivers F·(r + h) (the ramps' triangles add to F·r);
    # the grid's interval means add to the exact impulse (to rounding)
    press = Press(0.1, 2.0, 0.3, 0.5)
    assert press.end_s == pytest.approx(0.1 + 2 * 0.3 + 0.5)
    fs = 8800.0
    force = ContactForce([press]).process(Block(0, int(2.0 * fs), fs), {})["contact_force_N"]
    assert force.sum() / fs == pytest.approx(2.0 * (0.3 + 0.5), rel=1e-9)
    # a Touch's (and a placed press's) piecewise-linear force (what its electrodes feel) is the derivative of the
    # cumulative it shares with Press (what the fluid feels); 1 µN covers the base class's central difference
    from emulator.stimuli import ForceStimulus

    touch = Touch(0.1, 2.0, 0.3, 0.5)
    t = np.linspace(0.0, 2.0, 2001)
    assert touch.force(t) == pytest.approx(ForceStimulus.force(touch, t), abs=1e-6)


def test_a_sweeps_measured_frequency_follows_the_logarithmic_law_and_frequency_at():
    # log sweep: f(τ) = f0·(f1/f0)^(τ/T).  Measured as 1/period between upward zero crossings at the period's middle
    # (for a log sweep that reads f within (k·P)²/24, k = ln(f1/f0)/T: under 0.05 % above 50 Hz); 1 % tolerance
    v = Vibration(0.0, 1.0, 1e-6, 10.0, 900.0, fade_s=0.0)
    fs = 1e6
    t = np.arange(int(fs)) / fs
    y = v.value(t)
    up = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    crossings = t[up] - y[up] / (y[up + 1] - y[up]) / fs  # linear interpolation of each crossing
    mid, measured = 0.5 * (crossings[1:] + crossings[:-1]), 1.0 / np.diff(crossings)
    keep = measured > 50.0
    assert keep.sum() > 100
    assert measured[keep] == pytest.approx(10.0 * 90.0 ** mid[keep], rel=0.01)
    assert measured[keep] == pytest.approx(v.frequency_at(mid[keep]), rel=0.01)


def test_stimuli_fade_in_with_a_raised_cosine_and_keep_their_shape_wherever_they_start():
    # raised-cosine fade of length f: (1 − cos(π·τ/f))/2 = sin²(π·τ/(2f)): sin²(π/8) ≈ 0.146 a quarter in, 1/2 halfway
    q = np.sin(np.pi / 8) ** 2
    for start in (0.0, 0.0123):
        cal = PressureCalibrator(start, 1.0, offset_Pa=100.0, fade_s=0.02)
        assert cal.value(start + np.array([0.005, 0.01, 0.5, 0.995])) == pytest.approx(100.0 * np.array([q, 0.5, 1, q]),
                                                                                         rel=1e-9)
        # a tone counts its phase from its own start: the same waveform whenever it starts (1e-9 of the amplitude:
        # rounding of start + τ − start)
        tau = np.linspace(0.0, 1.0, 1001)
        tone = Vibration(start, 1.0, 1e-6, 100.0, fade_s=0.02).value(start + tau)
        assert tone == pytest.approx(Vibration(0.0, 1.0, 1e-6, 100.0, fade_s=0.02).value(tau), abs=1e-15)
    # without a fade a tone is cut at its end: nothing after it
    abrupt = Vibration(0.0, 0.5, 1e-6, 100.0, fade_s=0.0)
    assert np.all(abrupt.value(np.array([0.5025, 0.6025, 1.0025])) == 0.0)
    assert abrupt.value(np.array([0.4975]))[0] == pytest.approx(-1e-6, rel=1e-9)  # sin(2π·100·0.4975) = −1


def test_the_reference_profiles_second_stage_noise_is_its_own_density_through_the_stage2_gain():
    from dataclasses import replace

    # first stage noiseless: PAC carries the second stage's input noise alone, white to fs/2 (per-sample RMS
    # density·√(fs/2)), through the 10 Hz high-pass (passes ≈ 99.96 % of that band's power) and the gain 99.1;
    # 21 000 samples (after 0.1 s) estimate an RMS within 0.5 % (1σ): 3 % tolerance
    p = replace(SensorParams(), amp_voltage_noise_V_per_rtHz=0.0, amp_current_noise_A_per_rtHz=0.0,
                stage2_voltage_noise_V_per_rtHz=1e-7)
    only_grid = NoiseSources(johnson=False, mains_hum=False, adc=False, spi_coupling=False, thermistor=False)
    s = Sensor(p, channels_read=["PAC"], fidelity="reference", noise=only_grid, seed=3)
    t = np.arange(28000) / s.fs  # at the grid samples (halfway between, interpolation would average two draws)
    pac = s.analog(np.zeros(t.size, int), t)
    expected = 1e-7 * np.sqrt(s.fs / 2) * p.stage2_gain
    assert pac[t > 0.1].std() == pytest.approx(expected, rel=0.03)  # (after the high-pass has settled)
    # the amplifier switch turns the second stage's noise off with the first's: PAC then sits at its bias
    quiet = Sensor(p, channels_read=["PAC"], fidelity="reference", noise=NoiseSources.none())
    assert np.all(quiet.analog(np.zeros(t.size, int), t) == pytest.approx(p.stage2_bias_V, abs=1e-9))


def test_a_sweep_reaching_beyond_the_grids_band_is_refused_whichever_way_it_goes():
    # a sweep's top frequency is at one of its ends: 5 kHz is past the default grid's Nyquist frequency (8800 Hz / 2)
    # and would alias, whether the sweep starts or ends there; a sweep within the band is built
    for f_start, f_stop in ((100.0, 5000.0), (5000.0, 100.0)):
        with pytest.raises(ValueError, match="finer grid"):
            Sensor(stimuli=[Vibration(0.0, 1.0, 1e-6, f_start, f_stop)], channels_read=["PAC"])
    Sensor(stimuli=[Vibration(0.0, 1.0, 1e-6, 100.0, 1000.0)], channels_read=["PAC"])


def test_the_effects_report_gives_each_effects_cost_per_simulated_second():
    """record.json's effects table (Sensor.effects_report): each row's ``seconds_per_simulated_s`` is its wall
    seconds over the seconds simulated (2 s here), the graph's effects and the slow models (electrodes) alike."""
    s = Sensor(stimuli=[Tap(0.5, 1.0)], channels_read=["PAC", "E1"])
    t = np.arange(8800) / 4400.0
    s.sample(np.where(np.arange(t.size) % 2, 0, 17), t)
    rows = s.effects_report()
    assert s.simulated_s == pytest.approx(2.0, abs=0.01)
    assert {"electrodes"} < {r["name"] for r in rows} and any(r["seconds"] > 0 for r in rows)
    for r in rows:
        assert r["seconds_per_simulated_s"] == pytest.approx(r["seconds"] / s.simulated_s, rel=1e-12), r["name"]

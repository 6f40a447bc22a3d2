"""Per-channel noise (issue 10.2): ADC input noise common to every channel, reference noise proportional to the
code, the PAC path's own extra noise, mains hum with harmonics carried exactly across blocks."""

import numpy as np
import pytest

from emulator import channels as ch
from emulator.adc import Adc
from emulator.conversions import ADC_LSB_V as LSB
from emulator.effects import Block, effect_rng
from emulator.extrinsic import MainsHum, hum_components
from emulator.noise_budget import budget, channel_totals
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor

QUIET = ["PDC", "TDC", "TAC"] + [f"E{n}" for n in range(1, 20)]


def test_adc_input_noise_is_its_parameter_on_every_channel():
    """A constant input on a quiet channel reads with √(σ_adc² + (ppm·code)² + 1/12) LSB RMS."""
    p = SensorParams()
    adc = Adc(p, seed=5, noise=True, spi_coupling=False)
    n = 200000
    codes = adc.convert(np.full(n, 1000.3 * LSB), channels=np.full(n, ch.PDC)).astype(float)
    ref = p.adc_reference_noise_ppm * 1e-6 * 1000.3
    assert codes.std() == pytest.approx(np.sqrt(p.adc_noise_rms_bits**2 + ref**2 + 1 / 12), rel=0.02)
    assert codes.mean() == pytest.approx(1000.3, abs=0.01)


def test_reference_noise_grows_with_the_code():
    """Reference noise only (input noise 0): σ = ppm · code, so a code near full scale is noisier than one low."""
    p = SensorParams().replace(adc_noise_rms_bits=0.0, pac_path_noise_rms_bits=0.0, adc_reference_noise_ppm=1000.0)
    adc = Adc(p, seed=1, noise=True, spi_coupling=False)
    n = 100000
    lo = adc.convert(np.full(n, 500.0 * LSB)).astype(float)
    hi = adc.convert(np.full(n, 4000.0 * LSB)).astype(float)
    assert np.sqrt(hi.var() - 1 / 12) == pytest.approx(4.0, rel=0.05)  # 1000 ppm × 4000
    assert lo.std() < 0.7 and hi.std() > 3.5


def test_pac_path_noise_lands_on_pac_conversions_only_and_leaves_the_others_unchanged():
    p = SensorParams()
    n = 100000
    chans = np.where(np.arange(n) % 2 == 0, ch.PAC, ch.PDC)
    v = np.full(n, 2000.4 * LSB)
    a = Adc(p, seed=3, spi_coupling=False).convert(v, channels=chans).astype(float)
    b = Adc(p.replace(pac_path_noise_rms_bits=0.0), seed=3, spi_coupling=False).convert(v, channels=chans)
    assert np.array_equal(a[1::2], b[1::2].astype(float))  # PDC conversions identical with or without it
    expected = np.sqrt(p.adc_noise_rms_bits**2 + p.pac_path_noise_rms_bits**2 + 1 / 12)
    assert a[0::2].std() == pytest.approx(expected, rel=0.02)


def test_adc_rejects_mismatched_channels():
    with pytest.raises(ValueError, match="channels"):
        Adc(SensorParams(), seed=0).convert(np.zeros(4), channels=np.zeros(3, int))
    with pytest.raises(ValueError):  # σ alone: a shape that does not broadcast is refused, not read past its end
        Adc(SensorParams(), seed=0).sigma_V(np.zeros(6), np.zeros(2, int))


def test_one_channel_for_all_values_is_spread_over_them():
    """sigma_V(v, PAC) with a scalar channel: every value carries the PAC path's term, as an array of PACs gives."""
    adc, v = Adc(SensorParams(), seed=0), np.linspace(0.1, 3.0, 6)
    assert np.array_equal(adc.sigma_V(v, ch.PAC), adc.sigma_V(v, np.full(6, ch.PAC)))
    assert np.all(adc.sigma_V(v, ch.PAC) > adc.sigma_V(v, ch.PDC))


def test_quiet_channels_read_half_an_lsb_and_pac_1_4_bits_at_rest():
    """Through the sensor's own sampling at the default frame's instants."""
    names = list(ch.DEFAULT_FRAME_NAMES)
    s = Sensor(channels_read=set(names), seed=11)
    idx = np.array([ch.channel_index(x) for x in names])
    frames = 2000
    t = (np.arange(frames * idx.size) / ch.DEFAULT_SLOT_RATE_HZ) + 0.1
    codes = s.sample(np.tile(idx, frames), t).astype(float)
    chans = np.tile(idx, frames)
    for name in QUIET:
        sd = codes[chans == ch.channel_index(name)].std()
        assert 0.3 <= sd <= 0.7, (name, sd)
    assert codes[chans == ch.PAC].std() == pytest.approx(1.4, abs=0.1)


def test_budget_covers_every_channel_and_agrees_with_the_measurement():
    totals = channel_totals(budget())
    assert set(totals) == {"PAC", *QUIET}
    assert totals["PAC"] == pytest.approx(1.4, abs=0.05)
    for name in QUIET:
        if name != "TAC":  # TAC carries the thermistor noise only while the thermal network runs
            assert 0.45 <= totals[name] <= 0.6, name


def _hum(params, seed, block_n, total_n, fs=8800.0):
    h = MainsHum(params, seed)
    out = [h.process(Block(n0, min(block_n, total_n - n0), fs), {})["stage1_input_V"]
           for n0 in range(0, total_n, block_n)]
    return np.concatenate(out)


@pytest.mark.parametrize("mains", [50.0, 60.0])
def test_hum_has_its_fundamental_and_2nd_and_3rd_harmonics_at_their_amplitudes(mains):
    p = SensorParams().replace(mains_frequency_Hz=mains)
    fs, n = 8800.0, 8800
    x = _hum(p, 4, 1000, n, fs)
    spec = np.abs(np.fft.rfft(x)) * 2 / n
    f = np.fft.rfftfreq(n, 1 / fs)
    a1 = p.mains_amplitude_V
    lines = {mains: a1, 2 * mains: a1 * p.mains_harmonic2_ratio, 3 * mains: a1 * p.mains_harmonic3_ratio}
    for fk, a in lines.items():  # from the parameters, not from the generator's own table
        assert spec[np.argmin(np.abs(f - fk))] == pytest.approx(a, rel=1e-6), fk
    others = np.ones_like(spec, bool)
    for fk in lines:
        others[np.argmin(np.abs(f - fk))] = False
    assert spec[others].max() < 1e-6 * p.mains_amplitude_V


def test_hum_phase_is_carried_exactly_across_blocks_and_far_into_a_run():
    p = SensorParams()
    a = _hum(p, 9, 8800, 3 * 8800)
    b = _hum(p, 9, 1237, 3 * 8800)
    assert np.array_equal(a, b)  # each sample from its absolute index: the same bits whatever the blocks
    # ten hours in, a block still continues the same three sinusoids
    fs, n0 = 8800.0, int(10 * 3600 * 8800)
    h = MainsHum(p, 9)
    late = h.process(Block(n0, 64, fs), {})["stage1_input_V"]
    phases = effect_rng(9, "mains_hum").uniform(0, 2 * np.pi, 3)  # the generator's own stream
    exact = sum(a * np.sin(2 * np.pi * ((fk * (n0 + np.arange(64))) % fs) / fs + ph)
                for (_, fk, a), ph in zip(hum_components(p), phases))
    assert np.max(np.abs(late - exact)) < 1e-6 * p.mains_amplitude_V


def test_hum_off_removes_fundamental_and_harmonics_only():
    """Random streams are keyed by effect name: leaving the hum out changes PAC only by the three hum lines."""
    t = np.arange(4400) / 4400.0
    with_hum = Sensor(channels_read=["PAC"], seed=5, noise=NoiseSources(adc=False)).analog(np.zeros(4400, int), t)
    without = Sensor(channels_read=["PAC"], seed=5, noise=NoiseSources(adc=False, mains_hum=False)).analog(
        np.zeros(4400, int), t)
    diff = (with_hum - without) / LSB
    spec = np.fft.rfft(diff)
    f = np.fft.rfftfreq(diff.size, 1 / 4400)
    assert f[np.argmax(np.abs(spec))] == pytest.approx(60.0, abs=1.0)  # D's lab: 60 Hz mains by default
    keep = np.zeros_like(spec)
    for _, fk, _ in hum_components(SensorParams()):
        k = np.argmin(np.abs(f - fk))
        keep[k] = spec[k]
    residue = diff - np.fft.irfft(keep, diff.size)
    assert np.std(residue) < 0.05 * np.std(diff)  # the old fundamental-only check would leave 15 % (3rd harmonic)


def test_the_compiled_conversion_noise_is_numpys_formula_to_the_bit():
    """(consistency) The ADC's per-conversion noise (one compiled pass) is numpy's σ = √(σ_adc² + (ppm·v)² +
    σ_PAC²·[PAC]) times the conversion's float32 standard-normal draw, added to the value, to the bit: σ itself
    (:meth:`Adc.sigma_V`, with and without channels) and the codes of :meth:`Adc.convert`."""
    from emulator.adc import Adc, quantize
    from emulator.effects import effect_rng

    p = SensorParams()
    rng = np.random.default_rng(8)
    v = rng.uniform(0.0, 3.3, 3000)
    channels = rng.choice([ch.PAC, ch.PDC, ch.TDC, ch.ELECTRODE_FIRST], v.size)
    adc = Adc(p, seed=4, spi_coupling=False)
    noise_var, rel, pac_var = adc.noise_V**2, adc.reference_rel, adc.pac_V**2
    base = noise_var + np.square(rel * v)
    sigma = np.sqrt(base + pac_var * (channels == ch.PAC))
    np.testing.assert_array_equal(adc.sigma_V(v, channels), sigma)
    np.testing.assert_array_equal(adc.sigma_V(v), np.sqrt(base))
    z = effect_rng(4, "adc_noise").standard_normal(v.size, dtype=np.float32)
    np.testing.assert_array_equal(adc.convert(v, channels=channels), quantize(v + sigma * z))


def _lines(params=None) -> dict[str, float]:
    return {x.source: x.pac_bits for x in budget(params)}


def test_the_budget_prints_pa_on_the_published_pac_scale():
    """The Pa column is PAC bits × D's 0.37 Pa per bit (Table 4-1, ± 2 %): the header's scale and every line's."""
    from emulator.conversions import PAC_PA_PER_BIT
    from emulator.noise_budget import format_budget

    text = format_budget(budget())
    scale = float(text.splitlines()[0].split("1 bit = ")[1].split(" Pa")[0])
    assert scale == pytest.approx(PAC_PA_PER_BIT, rel=0.02)
    total = next(line for line in text.splitlines() if line.startswith("total at the ADC output")).split()
    assert float(total[6]) == pytest.approx(float(total[7]) * scale, abs=1e-3)  # Pa column = bits × scale


def test_the_adc_input_noise_is_a_12_bit_enob_of_11_1_less_quantization():
    """README (noise budget): the ADC's 0.45 LSB comes from a 12-bit ENOB of 11.1 less quantization. An ENOB of N bits
    on a 12-bit converter means a total noise of 2^(12 − N)/√12 LSB RMS (quantization included); what remains once
    the 1/√12 LSB of quantization is taken out is the input noise the budget's "ADC input noise" line must show."""
    total = 2 ** (12 - 11.1) / np.sqrt(12)
    expected = np.sqrt(total**2 - 1 / 12)  # 0.455 LSB
    lines = _lines()
    assert lines["ADC input noise (every channel)"] == pytest.approx(expected, abs=0.01)
    assert lines["ADC quantization"] == pytest.approx(1 / np.sqrt(12), rel=1e-9)


def test_the_hum_harmonics_and_reference_noise_lines_are_the_documented_fractions():
    """README (noise budget): the 2nd harmonic of the hum is 0.04 × the fundamental (2 × IEC 61000-2-2's 2 %), the 3rd
    0.15 × (3 × its 5 %) — the induced hum grows with frequency — and the reference noise is 20 ppm of PAC's resting
    code 2048. Compared as referred-to-input amplitudes (a hum line is narrow, so the band does not change it)."""
    rti = {x.source: x.rti_uV for x in budget()}
    bits = _lines()
    fundamental = rti["mains hum (60 Hz)"]
    assert rti["mains hum, 2nd harmonic (120 Hz)"] == pytest.approx(2 * 0.02 * fundamental, rel=1e-9)
    assert rti["mains hum, 3rd harmonic (180 Hz)"] == pytest.approx(3 * 0.05 * fundamental, rel=1e-9)
    assert bits["ADC reference noise at the resting code"] == pytest.approx(20e-6 * 2048, rel=0.01)


def test_every_total_is_the_quadrature_sum_of_the_lines_it_lists():
    """No source is dropped from, or added to, a channel's total: PAC's total is the intrinsic total, the hum lines and
    the ADC's four lines in quadrature (the intrinsic total itself that of its three Table 5-1 sources); each quiet
    channel's total is its own rows'."""
    lines = _lines()
    intrinsic = ("bridge Johnson noise", "amplifier voltage noise", "amplifier current noise × R")
    assert lines["intrinsic total (Table 5-1)"] == pytest.approx(np.sqrt(sum(lines[k] ** 2 for k in intrinsic)), rel=1e-12)
    pac = ["intrinsic total (Table 5-1)", "ADC quantization", "ADC input noise (every channel)",
           "ADC reference noise at the resting code", "PAC path extra noise (stage 2 / ADC driver)", "SPI coupling"]
    pac += [k for k in lines if k.startswith("mains hum")]
    assert lines["total at the ADC output"] == pytest.approx(np.sqrt(sum(lines[k] ** 2 for k in pac)), rel=1e-12)
    for name in QUIET:
        rows = [v for k, v in lines.items() if k.startswith(f"{name}: ") and not k.endswith("total at the ADC output")]
        assert len(rows) >= 4 and lines[f"{name}: total at the ADC output"] == pytest.approx(
            np.sqrt(sum(v**2 for v in rows)), rel=1e-12), name


def test_the_pdc_path_line_is_the_intrinsic_noise_over_the_stage1_band_times_its_gain():
    """Derived: the Table 5-1 density over a 2nd-order Butterworth's noise bandwidth, (π/4)/sin(π/4) × its corner
    (closed form, not the budget's numerical integral), times the stage-1 gain, in LSB."""
    p = SensorParams()
    density = np.sqrt(p.johnson_noise_V_per_rtHz**2 + p.amp_voltage_noise_V_per_rtHz**2
                      + (p.amp_current_noise_A_per_rtHz * p.bridge_resistance_ohm) ** 2)
    enbw = np.pi / 4 / np.sin(np.pi / 4) * p.stage1_lowpass_Hz
    expected = density * np.sqrt(enbw) * p.stage1_gain / LSB
    assert _lines(p)["PDC: intrinsic noise × stage-1 gain"] == pytest.approx(expected, rel=0.01)


def test_the_thermistor_lines_are_what_the_running_thermal_network_measures():
    """TDC and TAC carry the thermistor noise the network adds (a noisy run minus the same run without it, 600 s at
    the network's 100 Hz): each within 10 % of its budget line — TAC's ×98 gain and high-pass included."""
    from emulator import thermal

    p = SensorParams()
    t = np.arange(0.0, 600.0, 1.0 / thermal.THERMAL_RATE_HZ)
    noisy = thermal.ThermalModel(p, thermal.ThermalEvents([]), seed=3).values_at(t)
    quiet = thermal.ThermalModel(p, thermal.ThermalEvents([]), seed=3, noise=False).values_at(t)
    settled = t > 20.0  # past the TAC high-pass's settling (0.45 Hz)
    measured = (noisy - quiet)[settled].std(axis=0) / LSB
    lines = _lines(p)
    assert measured[1] == pytest.approx(lines["TDC: thermistor noise (thermal network running)"], rel=0.1)
    assert measured[2] == pytest.approx(lines["TAC: thermistor noise (thermal network running)"], rel=0.1)


def test_spi_coupling_draws_from_the_scene_seed_and_follows_its_own_switch():
    p = SensorParams()
    v = np.full(4000, 1.65)
    busy = np.ones(v.size, bool)
    # coupling alone (conversion noise off): σ = spi_coupling_rms_V, plus rounding's 1/12 LSB²; 4000 draws estimate
    # an RMS within 1.1 % (1σ): 5 % tolerance
    alone = Adc(p, 1, noise=False).convert(v, bus_active=busy).astype(float)
    assert alone.std() == pytest.approx(np.sqrt((p.spi_coupling_rms_V / LSB) ** 2 + 1 / 12), rel=0.05)
    # the scene seed keys the disturbance: the same seed repeats it, another seed draws another one
    assert np.array_equal(Adc(p, 1, noise=False).convert(v, bus_active=busy), alone)
    assert not np.array_equal(Adc(p, 2, noise=False).convert(v, bus_active=busy), alone)
    # its switch turns the coupling off and leaves the conversion noise: a busy bus then changes no code
    off = Adc(p, 1, spi_coupling=False)
    assert np.array_equal(off.convert(v, bus_active=busy), Adc(p, 1, spi_coupling=False).convert(v))


def test_amplifier_voltage_and_current_noise_add_in_quadrature():
    from dataclasses import replace

    # independent sources add in power: with i·R equal to the voltage noise the first stage's input noise is √2 times
    # the voltage noise alone.  The same seed draws the same samples and PDC is a linear filter of them, so PDC's
    # deviation from rest scales by √2 exactly (1e-6 allows for rounding)
    base = SensorParams()
    v_only = replace(base, amp_current_noise_A_per_rtHz=0.0)
    both = replace(base, amp_current_noise_A_per_rtHz=base.amp_voltage_noise_V_per_rtHz / base.bridge_resistance_ohm)
    amp_only = NoiseSources(johnson=False, mains_hum=False, adc=False, spi_coupling=False, thermistor=False)
    t = np.arange(4400) / 4400.0
    pdc = np.full(t.size, ch.PDC)

    def deviation(p):
        noisy = Sensor(p, channels_read=["PDC"], noise=amp_only, seed=5).analog(pdc, t)
        return noisy - Sensor(p, channels_read=["PDC"], noise=NoiseSources.none()).analog(pdc, t)

    assert deviation(both).std() / deviation(v_only).std() == pytest.approx(np.sqrt(2), rel=1e-6)

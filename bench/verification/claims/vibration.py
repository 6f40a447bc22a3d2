"""Vibration claims: PAC RMS proportional to drive amplitude, d_min of a few nanometres near the resonance, and
the sensor below the human threshold at every frequency (D ch. 5, Fig. 5-4).

d_min follows D eq. 5.3 with the background measured on the emulator itself: the largest 2 Hz band of 1 s PAC
spectra at rest (median over the seconds), as D measured its 0.2 bits², not a constant.  The sweep runs on the
1/3-octave grid (rounded to whole hertz), which does not contain the resonance parameter or the mains lines."""

from __future__ import annotations

import numpy as np

from bench.verification import analysis
from bench.verification.claims.core import Bench, Claim, claim_group
from bench.verification.psychophysics import human_threshold_m
from emulator.sensor import NoiseSources
from emulator.stimuli import Vibration

#: where the peak sensitivity must lie to count as "around its peak frequency sensitivity of 330Hz" (D ch. 5): the
#: resonance of units over 0.3–0.7 mL spans 313–339 Hz; the peak search covers 250–400 Hz
PEAK_NEAR_HZ = (300.0, 360.0)

#: drive frequencies (Hz) and amplitudes (m) of the proportionality row: D's band, its resonance, its top
PROPORTIONALITY_FREQUENCIES_HZ = (20, 100, 315, 630, 900)
PROPORTIONALITY_DRIVES_M = (0.5e-6, 1.0e-6, 2.0e-6, 4.0e-6)

#: 1/3-octave centre frequencies from 10 Hz (IEC 61260 nominal values, whole hertz) and D's top, 900 Hz
SWEEP_FREQUENCIES_HZ = (10, 13, 16, 20, 25, 32, 40, 50, 63, 80, 100, 125, 160, 200, 250, 315, 400, 500, 630, 800,
                        900)


@claim_group("vibration")
def vibration_claims(b: Bench) -> list[Claim]:
    """PAC RMS ∝ drive amplitude (R² ≥ 0.999); d_min ≤ 10 nm near resonance and below human thresholds."""
    rows = []
    r2_by_frequency, rms_by_frequency = {}, {}
    for f in PROPORTIONALITY_FREQUENCIES_HZ:
        rms = drive_rms_bits(b, PROPORTIONALITY_DRIVES_M, f)
        rms_by_frequency[float(f)] = rms
        r2_by_frequency[float(f)] = analysis.fit_proportional(PROPORTIONALITY_DRIVES_M, rms).r_squared
    worst_r2 = min(r2_by_frequency.values())
    rows.append(Claim("PAC RMS proportional to drive amplitude", "R² ≥ 0.999", worst_r2, 0.999, 1.0, "R² (worst f)",
                      "D ch. 5; §7", {"r_squared_by_frequency_Hz": r2_by_frequency, "drive_m": PROPORTIONALITY_DRIVES_M,
                                      "rms_bits_by_frequency_Hz": rms_by_frequency}, kind="consistency",
                      note="the displacement path is a linear system by construction; R² of a fit through the "
                           "origin (an offset lowers it) of each frequency's band RMS over the drives"))
    background = resting_background_bits2(b)
    powers = drive_band_powers_bits2(b)
    dmins = d_min_by_frequency_m(powers, background)
    res = b.params.resonance_at_inflation_Hz
    peak_powers = drive_band_powers_bits2(b, frequencies_Hz=peak_search_frequencies_Hz(b))
    peak = d_min_by_frequency_m(peak_powers, background)
    peak_Hz = min(peak, key=peak.get)
    # D: "a few nanometers ... around its peak frequency sensitivity of 330Hz": a peak at the search's edge, or
    # away from 330 Hz, is no peak near the resonance, and the row fails (NaN)
    near = peak[peak_Hz] if PEAK_NEAR_HZ[0] <= peak_Hz <= PEAK_NEAR_HZ[1] else float("nan")
    ratios = {f: float(human_threshold_m(f) / d) for f, d in dmins.items()}
    worst_f = min(ratios, key=ratios.get)
    rows.append(Claim("d_min near the 330 Hz resonance", "a few nm: 1–10 nm", near * 1e9, 1.0, 10.0, "nm",
                      "D ch. 5; §7",
                      {"d_min_m": dmins, "peak_search_d_min_m": peak, "peak_Hz": peak_Hz,
                       "background_bits2": background, "resonance_Hz": res, "band_power_bits2": powers,
                       "peak_search_band_power_bits2": peak_powers}, kind="prediction",
                      note="D eq. 5.3 with the background measured at rest on the emulator (the largest 2 Hz band, "
                           "which the calibrated mains hum dominates) and the displacement gain (force slope × an "
                           "assumed 1 N/mm fingertip stiffness, not tuned to d_min), at the peak sensitivity as D "
                           "measured it: the least d_min on a fixed 5 Hz grid over 250–400 Hz clear of mains "
                           "harmonics (the grid is not placed on the resonance parameter; a unit's own resonance, "
                           "320–345 Hz, falls between grid points at most 2.5 Hz away); the peak must lie within "
                           "300–360 Hz, or the row fails"))
    rows.append(Claim("sensor beats human threshold at every frequency", "human / d_min > 1", ratios[worst_f], 1.0,
                      np.inf, "worst ratio", "D Fig. 5-4; Bolanowski et al. 1988",
                      {"ratio_by_frequency": ratios, "worst_Hz": worst_f}, kind="prediction",
                      note="human thresholds from published data points (bench/verification/psychophysics.py: "
                           "Bolanowski et al. 1988, thenar eminence, 2.9 cm² contactor), interpolated in dB over "
                           "log-frequency; d_min as in the row above"))
    return rows


def resting_background_bits2(b: Bench, seconds: int = 20) -> float:
    """Median over ``seconds`` 1 s spectra of PAC at rest of the largest 2 Hz band (bits²): D's background."""
    rec = b.acquire([], float(seconds), sequence=("PAC",), slot_rate_Hz=2200.0, seed_offset=999)
    pac = rec["PAC"][1]
    return float(np.median([analysis.largest_2hz_band(pac[k * 2200:(k + 1) * 2200], 2200.0)[1]
                            for k in range(len(pac) // 2200)]))


def peak_search_frequencies_Hz(b: Bench, low_Hz: float = 250.0, high_Hz: float = 400.0, step_Hz: float = 5.0,
                               clear_of_mains_Hz: float = 3.0) -> tuple[float, ...]:
    """Drive frequencies (Hz) for finding the peak sensitivity, as D did ("including the peak sensitivity"): every
    ``step_Hz`` over ``low_Hz``–``high_Hz``, leaving out those within ``clear_of_mains_Hz`` of a mains harmonic (a
    hum line in the drive's 2 Hz band would read as response).  The grid is fixed, not placed on the resonance."""
    mains = b.params.mains_frequency_Hz
    grid = np.arange(low_Hz, high_Hz + step_Hz / 2, step_Hz)
    return tuple(float(f) for f in grid if abs(f - mains * round(f / mains)) > clear_of_mains_Hz)


def drive_band_power_bits2(b: Bench, drive_m: float, frequency_Hz: float, duration_s: float, seed_offset: int,
                           noise: NoiseSources = NoiseSources()) -> float:
    """PAC power (bits²) in the 2 Hz band at ``frequency_Hz`` of the 1 s spectrum from 1 s to 2 s into a sinusoidal
    drive of amplitude ``drive_m`` (m) at ``frequency_Hz`` (Hz), from 0 s to the record's end at ``duration_s`` (s),
    PAC read alone at 2.2 kS/s (the drive's power, plus whatever of ``noise`` and hum shares its band)."""
    rec = b.acquire([Vibration(0.0, duration_s, drive_m, float(frequency_Hz), fade_s=0.0)], duration_s,
                    sequence=("PAC",), slot_rate_Hz=2200.0, noise=noise, seed_offset=seed_offset)
    return analysis.band_power_2hz(rec["PAC"][1][2200:4400], 2200.0, float(frequency_Hz))


def drive_rms_bits(b: Bench, drives_m, frequency_Hz: float, noise: NoiseSources = NoiseSources()) -> list[float]:
    """PAC RMS (bits) in the 2 Hz band at ``frequency_Hz`` (Hz) for each drive amplitude of ``drives_m`` (m): the
    proportionality row's measurements (2.5 s records, one seed per frequency; ``noise``: the sources on)."""
    return [float(np.sqrt(drive_band_power_bits2(b, float(a), frequency_Hz, 2.5, int(frequency_Hz), noise)))
            for a in drives_m]


def drive_band_powers_bits2(b: Bench, drive_m: float = 1e-6,
                            frequencies_Hz=SWEEP_FREQUENCIES_HZ) -> dict[float, float]:
    """P_drive of D eq. 5.3 (bits²) at each drive frequency (Hz) of ``frequencies_Hz`` for a drive of ``drive_m``
    (m): :func:`drive_band_power_bits2` over 2 s records, one seed per frequency."""
    return {float(f): drive_band_power_bits2(b, drive_m, f, 2.0, 1000 + int(f)) for f in frequencies_Hz}


def d_min_by_frequency_m(band_powers_bits2: dict[float, float], background_bits2: float,
                         drive_m: float = 1e-6) -> dict[float, float]:
    """d_min (m) at each drive frequency (Hz) by D eq. 5.3, from the drive's band powers (bits², a drive of
    ``drive_m`` m) and the resting background (bits²)."""
    return {f: analysis.minimum_detectable_amplitude(drive_m, p, noise_band_bits2=background_bits2)
            for f, p in band_powers_bits2.items()}


def sensitivity_curve(b: Bench, drive_m: float = 1e-6, background: float | None = None,
                      frequencies_Hz=SWEEP_FREQUENCIES_HZ) -> dict[float, float]:
    """d_min (m) at each drive frequency (Hz) from a 1 µm drive, by D eq. 5.3 with the measured resting background."""
    background = resting_background_bits2(b) if background is None else background
    return d_min_by_frequency_m(drive_band_powers_bits2(b, drive_m, frequencies_Hz), background, drive_m)

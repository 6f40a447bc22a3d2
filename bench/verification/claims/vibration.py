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
from emulator.stimuli import Vibration

#: where the peak sensitivity must lie to count as "around its peak frequency sensitivity of 330Hz" (D ch. 5): the
#: resonance of units over 0.3–0.7 mL spans 313–339 Hz; the peak search covers 250–400 Hz
PEAK_NEAR_HZ = (300.0, 360.0)

#: 1/3-octave centre frequencies from 10 Hz (IEC 61260 nominal values, whole hertz) and D's top, 900 Hz
SWEEP_FREQUENCIES_HZ = (10, 13, 16, 20, 25, 32, 40, 50, 63, 80, 100, 125, 160, 200, 250, 315, 400, 500, 630, 800,
                        900)


@claim_group("vibration")
def vibration_claims(b: Bench) -> list[Claim]:
    """PAC RMS ∝ drive amplitude (R² ≥ 0.999); d_min ≤ 10 nm near resonance and below human thresholds."""
    rows = []
    r2_by_frequency = {}
    for f in (20, 100, 315, 630, 900):
        amps = np.array([0.5, 1.0, 2.0, 4.0])
        rms = []
        for a in amps:
            rec = b.acquire([Vibration(0.0, 2.5, a * 1e-6, float(f), fade_s=0.0)], 2.5, sequence=("PAC",),
                            slot_rate_Hz=2200.0, seed_offset=int(f))
            rms.append(np.sqrt(analysis.band_power_2hz(rec["PAC"][1][2200:4400], 2200.0, f)))
        r2_by_frequency[float(f)] = analysis.fit_proportional(amps, rms).r_squared
    worst_r2 = min(r2_by_frequency.values())
    rows.append(Claim("PAC RMS proportional to drive amplitude", "R² ≥ 0.999", worst_r2, 0.999, 1.0, "R² (worst f)",
                      "D ch. 5; §7", {"r_squared_by_frequency_Hz": r2_by_frequency}, kind="consistency",
                      note="the displacement path is a linear system by construction"))
    background = resting_background_bits2(b)
    dmins = sensitivity_curve(b, background=background)
    res = b.params.resonance_at_inflation_Hz
    peak = sensitivity_curve(b, background=background, frequencies_Hz=peak_search_frequencies_Hz(b))
    peak_Hz = min(peak, key=peak.get)
    # D: "a few nanometers ... around its peak frequency sensitivity of 330Hz": a peak at the search's edge, or
    # away from 330 Hz, is no peak near the resonance, and the row fails (NaN)
    near = peak[peak_Hz] if PEAK_NEAR_HZ[0] <= peak_Hz <= PEAK_NEAR_HZ[1] else float("nan")
    ratios = {f: float(human_threshold_m(f) / d) for f, d in dmins.items()}
    worst_f = min(ratios, key=ratios.get)
    rows.append(Claim("d_min near the 330 Hz resonance", "a few nm: 1–10 nm", near * 1e9, 1.0, 10.0, "nm",
                      "D ch. 5; §7",
                      {"d_min_m": dmins, "peak_search_d_min_m": peak, "peak_Hz": peak_Hz,
                       "background_bits2": background, "resonance_Hz": res}, kind="prediction",
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


def sensitivity_curve(b: Bench, drive_m: float = 1e-6, background: float | None = None,
                      frequencies_Hz=SWEEP_FREQUENCIES_HZ) -> dict[float, float]:
    """d_min (m) at each drive frequency (Hz) from a 1 µm drive, by D eq. 5.3 with the measured resting background."""
    background = resting_background_bits2(b) if background is None else background
    out = {}
    for f in frequencies_Hz:
        rec = b.acquire([Vibration(0.0, 2.0, drive_m, float(f), fade_s=0.0)], 2.0, sequence=("PAC",),
                        slot_rate_Hz=2200.0, seed_offset=1000 + int(f))
        p = analysis.band_power_2hz(rec["PAC"][1][2200:4400], 2200.0, float(f))
        out[float(f)] = analysis.minimum_detectable_amplitude(drive_m, p, noise_band_bits2=background)
    return out

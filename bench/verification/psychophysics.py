"""Human vibrotactile detection thresholds, for comparison with the sensor (D ch. 5, Fig. 5-4).

The curve is built from published data points, not from a shape of our choosing: each point below is
(frequency in Hz, threshold in dB re 1 µm peak displacement, source).  Between points the threshold is
interpolated linearly in dB over log-frequency; outside the measured range it is held at the end points (the
comparison never leaves 10–900 Hz by more than the last point).

Source: Bolanowski, S. J., Gescheider, G. A., Verrillo, R. T. & Checkosky, C. M. (1988). Four channels mediate
the mechanical aspects of touch. J. Acoust. Soc. Am. 84, 1680–1694 — the composite (lowest-channel) detection
threshold on the thenar eminence, 2.9 cm² contactor with a rigid surround, skin at 30 °C (their summary figure of
the four channels' threshold curves).  The values are readings of that published figure at the listed
frequencies (reading uncertainty about ± 3 dB); they could not be checked against a table with the tools of this
project, so a reader with the paper should confirm them.  The figure's minimum, about −20 dB (0.1 µm) near
250–300 Hz, agrees with Verrillo (1963, J. Acoust. Soc. Am. 35, 1962–1966) for the same contactor.

The BioTac's comparison in D used the fingertip of five subjects (D Fig. 5-4), whose thresholds are higher than
the thenar eminence's with a large contactor; the thenar data are therefore the harder bar for the sensor.
"""

from __future__ import annotations

import numpy as np

_B88 = "Bolanowski et al. 1988 (thenar, 2.9 cm², 30 °C), figure reading"

#: (frequency Hz, threshold dB re 1 µm peak, source) — published data points
HUMAN_THRESHOLD_POINTS: tuple[tuple[float, float, str], ...] = (
    (10.0, 19.0, _B88),   # NP I channel region (flat-ish, falling slowly)
    (20.0, 14.0, _B88),
    (40.0, 7.0, _B88),    # P and NP I cross near 40 Hz
    (80.0, -6.0, _B88),   # P channel, falling ~12 dB/octave
    (150.0, -16.0, _B88),
    (250.0, -21.0, _B88),  # P minimum (≈ 0.09 µm); Verrillo 1963 gives ≈ −20 dB for the same contactor
    (300.0, -21.0, _B88),
    (500.0, -13.0, _B88),  # rising again above the best frequency
    (700.0, -6.0, _B88),
    (1000.0, 3.0, _B88),
)


def human_threshold_m(frequency_Hz) -> np.ndarray:
    """Human detection threshold (peak displacement, m) at each frequency (Hz), from the published points."""
    f = np.asarray(frequency_Hz, float)
    fp = np.log10([x[0] for x in HUMAN_THRESHOLD_POINTS])
    db = np.interp(np.log10(np.maximum(f, 1e-6)), fp, [x[1] for x in HUMAN_THRESHOLD_POINTS])
    return 1e-6 * 10 ** (db / 20.0)

"""Human vibrotactile detection thresholds, for comparison with the sensor (D ch. 5, Fig. 5-4).

Piecewise approximation of the classic U-shaped threshold curve of the Pacinian channel,
displacement in dB re 1 µm peak:

* Verrillo, R. T. (1963). Effect of contactor area on the vibrotactile threshold.
  J. Acoust. Soc. Am. 35, 1962–1966.  With large contactors the threshold is flat up to ~40 Hz,
  then falls at 12 dB/octave to its minimum near 250 Hz (as summarised by Gescheider & Verrillo).
* Minimum of −20 dB re 1 µm (0.1 µm) near 250 Hz: the Pacinian sensitivity to sub-micrometre
  vibration cited in D ch. 5 (Brisben et al. 1999; Westling & Johansson 1987).
* Above 250 Hz the threshold rises again; we take the mirror slope, +12 dB/octave (model choice).

This is an approximation of published curves, not a data set: it serves as the "human" bar the
sensor must beat.
"""

from __future__ import annotations

import numpy as np

BEST_FREQUENCY_HZ = 250.0
BEST_THRESHOLD_DB = -20.0  # re 1 µm
FLAT_BELOW_HZ = 40.0
SLOPE_DB_PER_OCTAVE = 12.0


def human_threshold_m(frequency_Hz) -> np.ndarray:
    """Approximate human detection threshold (peak displacement, m) at each frequency."""
    f = np.asarray(frequency_Hz, float)
    octaves_from_best = np.log2(np.maximum(f, FLAT_BELOW_HZ) / BEST_FREQUENCY_HZ)
    db = BEST_THRESHOLD_DB + SLOPE_DB_PER_OCTAVE * np.abs(octaves_from_best)
    return 1e-6 * 10 ** (db / 20.0)

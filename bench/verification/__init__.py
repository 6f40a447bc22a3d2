"""Measurements and verdicts: signal analysis (detection rule, fits, spectra), the published-figure claims, the human threshold curve, and the benchmarks of cost and error."""

"""The published figures (SENSOR.md), each measured on the emulator's output, checked with a tolerance and
labelled with the kind of evidence it is (prediction, calibrated, derived, consistency) and its source.

Every claim runs the sensor through the real path a host sees (sensor -> SPI peripheral -> host
sampler -> decoded codes), except the ones the dissertation states *before* the ADC, which read the
analog PAC node.  ``scripts/claims`` prints the table; the test suite runs the same functions.

Layout: :mod:`.core` holds ``Claim``, ``Bench``, the registry ``CLAIM_GROUPS`` (filled by the decorator
``@claim_group("name")``), ``run_claims`` and ``format_table``; one module per group registers itself when
imported.  Every module of this package is imported here, so a new group module (e.g. ``textures.py``)
registers itself without editing this file; the shipped groups come first, in the order below.
"""

from __future__ import annotations

import importlib
import pkgutil

from bench.verification.claims.core import (  # noqa: F401  (public names)
    CLAIM_GROUPS, KINDS, Bench, Claim, Spread, claim_group, format_spread_table, format_table, kind_counts,
    run_claims, run_claims_over_seeds)
from bench.verification.claims.noise import noise_claims  # noqa: F401
from bench.verification.claims.scales import scale_claims  # noqa: F401
from bench.verification.claims.force import force_claims  # noqa: F401
from bench.verification.claims.impact import impact_ring_claims  # noqa: F401
from bench.verification.claims.detection import detection_claims  # noqa: F401
from bench.verification.claims.false_detection import false_detection_claims  # noqa: F401
from bench.verification.claims.vibration import SWEEP_FREQUENCIES_HZ, sensitivity_curve, vibration_claims  # noqa: F401
from bench.verification.claims.thermal import THERMAL_MATERIALS, thermal_claims  # noqa: F401
from bench.verification.claims.electrodes import electrode_claims  # noqa: F401

for _info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
    if not _info.name.startswith("_"):
        importlib.import_module(f"{__name__}.{_info.name}")
del _info

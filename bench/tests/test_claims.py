"""Every published figure of SENSOR.md, measured on the emulator (the same checks as scripts/claims)."""

import pytest

from bench.verification.claims import CLAIM_GROUPS, Bench

pytestmark = pytest.mark.claims

_results = {}


def _claims(group):
    if group not in _results:
        _results[group] = CLAIM_GROUPS[group](Bench())
    return _results[group]


@pytest.mark.parametrize("group", list(CLAIM_GROUPS))
def test_published_figures_hold(group):
    failed = [f"{c.name}: {c.result}: expected {c.expected}, measured {c.measured:.4g} {c.unit}, accepted {c.tolerance}"
              for c in _claims(group) if not c.ok]
    assert not failed, "\n".join(failed)
    assert _claims(group), "a claim group that checks nothing"


# The review of issue 11: which rows are read-backs, calibrations or arithmetic, and must not pose as predictions.
EXPECTED_KINDS = {
    "PAC noise at rest, all sources": "calibrated",  # pac_path_noise_rms_bits tuned to 1.4 bits
    "PDC noise at rest": "prediction",  # ADC datasheet noise + reference + quantization (issue 10.2)
    "TDC noise at rest": "prediction",
    "TAC noise at rest": "prediction",
    "electrode noise at rest (E1..E19, farthest from 0.5)": "prediction",
    "TAC noise at rest, thermal network running": "prediction",  # documented deviation (tdc_noise_V)
    "mains harmonics (2nd, 3rd) visible in PAC at rest": "consistency",  # harmonics are parameters
    "largest 2 Hz band of a 1 s PAC spectrum at rest": "calibrated",  # hum amplitude tuned to 0.2 bits²
    "intrinsic noise referred to input": "derived",  # the intrinsic noise again, in µV
    "intrinsic noise in pressure": "derived",  # ... and in Pa
    "PAC range (half-span)": "derived",  # 2048 × the PAC scale
    "PDC code at full transducer range 103.4 kPa": "consistency",  # tolerance = the whole ADC range
    "force per PDC bit, 0–2 N": "calibrated",  # skin_direct_stiffness_N_per_m; the bridge/gain/ADC still enter
    "linearity of force -> PDC, 0–2 N": "calibrated",  # skin_relaxed_modulus_fraction (R² near 0.995)
    "PDC creep under a held 1 N, 0.2 → 10 s": "consistency",  # bounds on a model choice; D has no figure
    "PDC hysteresis loop, 0–2 N at 0.5 N/s": "consistency",
    "slope above the knee / slope below": "consistency",
    "impact ringing frequency": "calibrated",  # resonance_Hz anchors the skin's moving mass at 0.5 mL
    "impact ringing decay time constant": "calibrated",  # resonance_decay_s anchors the skin's loss factor
    "impact ringing over 0.3–0.7 mL: lowest": "prediction",
    "impact ringing over 0.3–0.7 mL: highest": "prediction",
    "ringing frequency change 0.4 → 0.6 mL": "prediction",
    "impact ring amplitude / momentum change m·v·(1+e)": "consistency",  # the model's own impulse formula
    "the sphere missed at 7 cm is detected from higher": "prediction",  # deviates: the air caps its speed
    "detection threshold spread: energy / momentum": "prediction",  # a documented deviation from D
    "false detections at rest": "consistency",  # P ≈ 1e-9 per window
    "settled thermistor above ambient": "consistency",  # heater_rise_K
    "TDC conversion error over 0–70 °C": "consistency",
    "a 1 N contact's change stays in the nearest 4 electrodes": "calibrated",  # bulge_width_ratio
    "a contact's electrode pattern locates it": "prediction",
    "a 1 N contact's PDC rise": "consistency",
}


def test_every_claim_is_labelled_and_no_read_back_poses_as_a_prediction():
    from bench.verification.claims import KINDS

    claims = {c.name: c for group in CLAIM_GROUPS for c in _claims(group)}
    assert all(c.kind in KINDS and c.source for c in claims.values())
    assert all(c.calibration for c in claims.values() if c.kind == "calibrated")
    assert all(c.note for c in claims.values() if c.kind == "consistency"), "say why a row is only a consistency check"
    wrong = {n: (claims[n].kind, k) for n, k in EXPECTED_KINDS.items() if claims[n].kind != k}
    assert not wrong, wrong

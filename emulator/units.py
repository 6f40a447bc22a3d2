"""Sensor units: a population of real devices, each drawn from documented manufacturing spreads.

A unit is a :class:`~emulator.params.SensorParams` (``SensorParams().replace(...)``) plus a serial number.  It is
drawn deterministically from a *unit seed* (a whole number ≥ 0) or from a serial number; the nominal unit (seed
``None`` or ``"nominal"``) is ``SensorParams()`` exactly.  Each spread draws from its own random stream
(``effect_rng(seed, "unit.<name>")``), so adding a spread later leaves every other unit value unchanged.

Spreads and their basis (σ of a normal draw clipped at ±3σ unless said otherwise):

* inflation volume — σ 0.03 mL around 0.5 mL.  D ch. 4 (assembly, Fig. 4-6): each skin is filled by hand with
  "approximately 0.5 cc" and corrected until the inflated height is 15.1 mm; D ch. 3 found the pressure/volume
  curve repeatable over five fillings (Fig. 3-4).  A few drops (30 µL) of filling is what the height check leaves.
  Moves the resting pressure (∝ V^1.5: ±9 %/σ ≈ ±10 PDC codes), and through the fluid's stiffness and layer
  mass the force slope and the resonance (:func:`emulator.mechanics.skin_fluid`).
* bridge null offset — σ 1 mV/V (±10 mV at 10 V excitation, ±124 PDC codes after the gain of 10).  An
  uncompensated MEMS piezoresistive bridge (D: Honeywell 24PC15SMT) is sold with its null offset as a band of
  a few mV/V; the 24PC sheet itself was not in reach of the search tool, so the band is the generic one of
  uncompensated silicon bridges, clipped so PDC at rest stays well inside 0..4095.
* bridge span — σ 0.25 %, clipped at ±0.7 %.  A datasheet band of an uncompensated bridge is wider (several %);
  the published scales (0.0365 kPa/PDC bit, 0.37 Pa/PAC bit) are checked to ±2 %, and the nominal model's PDC
  scale (36.96 Pa/bit from the published bridge, gain and LSB) already sits 1.3 % above D's 36.5, leaving 0.7 %.
  Deliberately narrow: see :data:`SPAN_SPREAD` (a choice forced by the claims, not a datum): a real population
  would scatter its scales by several %, which the bench's ±2 % tolerance on D Table 4-1 does not allow for.
  The span enters the force → PDC chain, so a unit's mN per PDC bit moves with it (±0.7 % at most).
* bridge offset and span drift — σ 20 % of their nominal values (uncompensated: drift is a property of the
  doping, which varies lot to lot).
* amplifier offsets — stage-1 bias σ 10 mV (op-amp input offset ~1 mV × gain 10, bias divider of 1 % resistors),
  stage-2 (PAC mid-scale) bias σ 10 mV (1.65 V from a 1 % divider: ±16 mV worst case).
* electrode geometry — ``electrode_gap_spread_mm`` = :data:`ELECTRODE_GAP_SPREAD_MM` and a per-unit
  ``electrode_gap_seed``: each electrode's resting fluid gap differs (skin thickness and core moulding, D ch. 4
  reports uneven skin thickness in moulded skins); 0.7 mm is sized on the electrode model (emulator/electrodes.py,
  gaps truncated at ±2σ): over 20 units the resting codes' 2nd–98th percentiles are 1900–3150 (0.5 mm gives
  2410–3100, 0.6 mm 2200–3130), each unit spanning ~1000 codes.
* thermistor — R25 uniform within ±1 % and Beta uniform within ±3 %: the tolerance letters of the part D names
  (Vishay NTCS0805E3474FXT: F = ±1 % on R25, X = ±3 % on B25/85).  A band, not a σ: parts are sorted into it.
* resonance — σ 5 Hz around 330 Hz at nominal inflation (``resonance_Hz`` anchors the skin's mass), clipped to
  the published 200–350 Hz: the skin's thickness and tension vary from moulding to moulding; the inflation adds
  its own shift.

Gains (stage 1: 10, stage 2: 99.1), the ADC and the noise parameters stay nominal: they are fixed by resistors of
0.1–1 % and the published noise figures are checked to ±10 %.
"""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass

import numpy as np

from emulator.effects import effect_rng
from emulator.params import SensorParams

NOMINAL = "nominal"
SERIAL_PREFIX = "BT"  # the host recognises a BioTac by this prefix
NOMINAL_SERIAL = "BTNOMINAL0000000"
_SEED_SERIAL = re.compile(r"^BTU(\d{13})$")
#: the form a BioTac SP reports a unit's serial in (emulator.spi.model.variant_serial): "BTSP" + the seed's last 12
#: digits, which hold every seed up to MAX_UNIT_SEED
_SP_SEED_SERIAL = re.compile(r"^BTSP(\d{12})$")
MAX_UNIT_SEED = 2**31 - 1
MAX_SERIAL_LENGTH = 16  # what the sensor's serial property holds (emulator/spi/model.py)

#: spread of each electrode's resting gap (mm) of a drawn unit, sized on the electrode model (module docstring)
ELECTRODE_GAP_SPREAD_MM = 0.7
INFLATION_SPREAD_ML = 0.03
BRIDGE_OFFSET_SPREAD_V_PER_V = 1.0e-3
SPAN_SPREAD = 0.0025
SPAN_LIMIT = 0.007
DRIFT_SPREAD = 0.20
STAGE1_BIAS_SPREAD_V = 0.010
STAGE2_BIAS_SPREAD_V = 0.010
THERMISTOR_R25_TOLERANCE = 0.01
THERMISTOR_BETA_TOLERANCE = 0.03
RESONANCE_SPREAD_HZ = 5.0


@dataclass(frozen=True)
class Unit:
    """One sensor unit: its serial number, its parameters and the seed it was drawn from (None: nominal)."""

    serial: str
    params: SensorParams
    seed: int | None = None

    @property
    def name(self) -> str:
        return NOMINAL if self.seed is None else str(self.seed)


def serial_for(seed: int | None) -> str:
    """The serial number of unit ``seed`` (16 characters, starting with "BT")."""
    return NOMINAL_SERIAL if seed is None else f"BTU{int(seed):013d}"


def _normal(seed: int, name: str, sigma: float, limit: float | None = None) -> float:
    limit = 3.0 * sigma if limit is None else limit
    return float(np.clip(effect_rng(seed, f"unit.{name}").normal(0.0, sigma), -limit, limit))


def _uniform(seed: int, name: str, half_width: float) -> float:
    return float(effect_rng(seed, f"unit.{name}").uniform(-half_width, half_width))


def draw_params(seed: int, base: SensorParams | None = None) -> SensorParams:
    """The parameters of unit ``seed``: ``base`` (default: nominal) with every manufacturing spread drawn."""
    p = base or SensorParams()
    resonance = p.resonance_Hz + _normal(seed, "resonance", RESONANCE_SPREAD_HZ)
    return p.replace(
        inflation_volume_mL=p.inflation_volume_mL + _normal(seed, "inflation", INFLATION_SPREAD_ML),
        bridge_offset_V_per_V=p.bridge_offset_V_per_V + _normal(seed, "bridge_offset", BRIDGE_OFFSET_SPREAD_V_PER_V),
        bridge_sensitivity_V_per_V_Pa=p.bridge_sensitivity_V_per_V_Pa
        * (1.0 + _normal(seed, "bridge_span", SPAN_SPREAD, SPAN_LIMIT)),
        bridge_offset_drift_V_per_V_K=p.bridge_offset_drift_V_per_V_K * (1.0 + _normal(seed, "offset_drift",
                                                                                       DRIFT_SPREAD)),
        bridge_span_drift_per_K=p.bridge_span_drift_per_K * (1.0 + _normal(seed, "span_drift", DRIFT_SPREAD)),
        stage1_bias_V=p.stage1_bias_V + _normal(seed, "stage1_bias", STAGE1_BIAS_SPREAD_V),
        stage2_bias_V=p.stage2_bias_V + _normal(seed, "stage2_bias", STAGE2_BIAS_SPREAD_V),
        electrode_gap_spread_mm=ELECTRODE_GAP_SPREAD_MM,
        electrode_gap_seed=int(effect_rng(seed, "unit.electrode_gap_seed").integers(0, MAX_UNIT_SEED)),
        thermistor_r25_ohm=p.thermistor_r25_ohm * (1.0 + _uniform(seed, "thermistor_r25", THERMISTOR_R25_TOLERANCE)),
        thermistor_beta_K=p.thermistor_beta_K * (1.0 + _uniform(seed, "thermistor_beta", THERMISTOR_BETA_TOLERANCE)),
        resonance_Hz=min(max(resonance, 200.0), 350.0),
    )


def seed_of_serial(serial: str) -> int | None:
    """The unit seed a serial number stands for: ``BTU`` + 13 digits is that seed, and so is ``BTSP`` + 12 digits
    (the serial a BioTac SP of that unit answers, so a serial read from an SP gives back its unit); the nominal
    serial is None; any other serial starting with "BT" seeds the draw through a hash of its text."""
    if problem := serial_problem(serial):
        raise ValueError(f"serial {_shown(serial)}: {problem}")
    if serial == NOMINAL_SERIAL:
        return None
    named = _named_seed(serial)
    if named is not None:
        return named  # (in range: serial_problem checked it)
    return int.from_bytes(hashlib.sha256(serial.encode()).digest()[:4], "little") & MAX_UNIT_SEED


def _form_problem(serial) -> str | None:
    if (not isinstance(serial, str) or not serial.startswith(SERIAL_PREFIX) or not 3 <= len(serial) <= MAX_SERIAL_LENGTH
            or not all(c.isascii() and (c.isalnum() or c in "-_") for c in serial)):
        return (f'a serial number starts with "{SERIAL_PREFIX}" and has 3 to {MAX_SERIAL_LENGTH} ASCII letters, '
                f"digits, '-' or '_'")
    return None


def serial_problem(serial) -> str | None:
    """Why ``serial`` is no unit's serial number (None if it is one), without quoting it, so a caller names it in its
    own spelling (a scene file's TOML): not "BT" then 1 to 14 letters, digits, '-' or '_'; or a serial of the seed
    form (``BTU`` + 13 digits, ``BTSP`` + 12) naming a seed above :data:`MAX_UNIT_SEED`."""
    if problem := _form_problem(serial):
        return problem
    named = _named_seed(serial)
    if named is not None and named > MAX_UNIT_SEED:
        return f"unit seed {named} is above {MAX_UNIT_SEED}"
    return None


def _named_seed(serial: str) -> int | None:
    """The seed a serial of the seed form names (in range or not), None for any other serial."""
    m = _SEED_SERIAL.match(serial) or _SP_SEED_SERIAL.match(serial)
    return int(m.group(1)) if m else None


def _shown(value) -> str:
    """``value`` for a message as the bench's messages spell a value: text in double quotes (its quotes, backslashes
    and control characters escaped as JSON escapes them, so ``BT x'y`` reads ``"BT x'y"``, never Python's
    ``'abc'``), anything else as Python writes it; cut after 50 characters when longer than 60."""
    text = json.dumps(value, ensure_ascii=False) if isinstance(value, str) else repr(value)
    return text if len(text) <= 60 else text[:50] + "…"


def check_serial(serial) -> None:
    """ValueError unless ``serial`` is a serial number: "BT" then 1 to 14 letters, digits, '-' or '_' (a seed it
    names is checked by :func:`seed_of_serial`)."""
    if problem := _form_problem(serial):
        raise ValueError(f"serial {_shown(serial)}: {problem}")


def unit(which=None, base: SensorParams | None = None) -> Unit:
    """Unit by seed (int ≥ 0), ``None``/``"nominal"`` (today's nominal sensor), a serial number ("BT...") or a
    seed given as text ("17").  ``base``: parameters the spreads are drawn around (default: nominal)."""
    base = base or SensorParams()
    if which is None or which == NOMINAL:
        return Unit(NOMINAL_SERIAL, base, None)
    if isinstance(which, str) and which.startswith(SERIAL_PREFIX):
        seed = seed_of_serial(which)
        return Unit(which, base if seed is None else draw_params(seed, base), seed)
    if isinstance(which, str) and which.isascii() and which.isdigit():  # ("²".isdigit(), but int("²") fails)
        which = int(which)
    if isinstance(which, bool) or not isinstance(which, (int, np.integer)) or not 0 <= which <= MAX_UNIT_SEED:
        raise ValueError(f"unit {_shown(which)}: a unit seed 0 to {MAX_UNIT_SEED}, \"{NOMINAL}\", or a serial number "
                         f"starting with \"{SERIAL_PREFIX}\"")
    return Unit(serial_for(int(which)), draw_params(int(which), base), int(which))


#: the parameters a unit draws (what ``biotac-bench units`` shows)
DRAWN_FIELDS = ("inflation_volume_mL", "bridge_offset_V_per_V", "bridge_sensitivity_V_per_V_Pa",
                "bridge_offset_drift_V_per_V_K", "bridge_span_drift_per_K", "stage1_bias_V", "stage2_bias_V",
                "electrode_gap_spread_mm", "electrode_gap_seed", "thermistor_r25_ohm", "thermistor_beta_K",
                "resonance_Hz")


def derived(p: SensorParams) -> dict[str, float]:
    """Figures a unit's parameters imply: resting pressure (Pa), resting PDC (V and code, no noise), resonance
    at its inflation (Hz), PDC scale (Pa per bit)."""
    from emulator.conversions import ADC_LSB_V

    pdc_V = p.stage1_bias_V + p.stage1_gain * (p.bridge_offset_V + p.resting_pressure_Pa * p.bridge_span_V_per_Pa)
    return {"resting_pressure_Pa": p.resting_pressure_Pa, "resting_PDC_V": pdc_V,
            "resting_PDC_code": pdc_V / ADC_LSB_V, "resonance_at_inflation_Hz": p.resonance_at_inflation_Hz,
            "PDC_Pa_per_bit": ADC_LSB_V / p.pdc_V_per_Pa}

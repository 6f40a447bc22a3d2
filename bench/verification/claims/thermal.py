"""Thermal claims: the thermistor settled about 10 °C above ambient, the TDC conversion (D eq. 4.4) and its
resolution and range, and cooling on contact ordered by the material's thermal properties."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from bench.verification.claims.core import Bench, Claim, claim_group
from emulator import conversions as conv
from emulator.stimuli import Touch
from emulator.thermal import BEAD, ThermalEvents, ThermalModel

#: ambient temperatures (°C) whose settled thermistor (≈ ambient + heater rise) spans 0–70 °C
SWEEP_AMBIENT_C = tuple(np.arange(-10.0, 60.01, 5.0))


def tdc_sweep(b: Bench, settings=tuple((a, None) for a in SWEEP_AMBIENT_C), offset=200) -> list[tuple[float, float]]:
    """(true thermistor °C, mean TDC code) of the settled sensor at each (ambient °C, heater rise K or None for
    the default) of ``settings``, the codes read through the ADC (noise on: the mean of 400 dithered codes
    resolves ~0.03 LSB)."""
    out = []
    for k, (amb, rise) in enumerate(settings):
        p = b.params.replace(ambient_temperature_C=float(amb))
        p = p if rise is None else p.replace(heater_rise_K=float(rise))
        bead = float(ThermalModel(p, ThermalEvents([]), seed=0).x[BEAD])
        rec = replace(b, params=p).acquire([], 4.0, sequence=("TDC",), slot_rate_Hz=100.0, seed_offset=offset + k)
        out.append((bead, float(np.mean(rec["TDC"][1]))))
    return out


def range_top_C(sweep: list[tuple[float, float]]) -> float:
    """Where the mean TDC code reaches 4094 (°C): the line through the last two unclipped (mean code < 4093.5)
    points of ``sweep`` ((thermistor °C, mean code), in rising temperature) extended to code 4094; inf when no point
    clips (the top was not reached, so the sweep cannot place it)."""
    unclipped = [(t, c) for t, c in sweep if c < 4093.5]
    if len(unclipped) == len(sweep):
        return float("inf")
    if len(unclipped) < 2:
        raise ValueError(f"the TDC range sweep has {len(unclipped)} unclipped point(s) below code 4094: two are "
                         "needed to place the top; start the sweep cooler")
    (t1, c1), (t2, c2) = unclipped[-2:]
    return float(t2 + (4094.0 - c2) * (t2 - t1) / (c2 - c1))


THERMAL_MATERIALS = ("aluminum", "glass", "wood", "polystyrene foam")

#: the instant (s) the material touches begin
TOUCH_START_S = 1.0
#: the record before this instant (s) is the rest (TDC's resting temperature, TAC's resting level)
REST_BEFORE_S = 0.9
#: the TAC-derived rate is a running mean over this long (s), which keeps the noise's own peaks (a few
#: 1e-4 °C/s at rest) under the weakest material's transient
TAC_SMOOTHING_S = 0.2


def material_touch(b: Bench, material: str | None, seed_offset: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(instants s, TDC codes, TAC codes) of a 1 N touch (6 mm indenter over E17) on ``material`` at room
    temperature from 1 s, held 10 s, TDC and TAC each read at 100 S/s for 11.5 s (``material`` None: a touch that
    exchanges no heat)."""
    touch = Touch(TOUCH_START_S, 1.0, 0.2, 10.0, electrode="E17", indenter_radius_mm=6.0, material=material)
    rec = b.acquire([touch], 11.5, sequence=("TDC", "TAC"), slot_rate_Hz=200.0, seed_offset=seed_offset)
    t, tdc = rec["TDC"]
    return t, tdc, rec["TAC"][1]


def tac_rate_C_per_s(t, tac, tdc, rest_before_s: float = REST_BEFORE_S,
                     smoothing_s: float = TAC_SMOOTHING_S) -> tuple[np.ndarray, np.ndarray]:
    """(instants s, rate of temperature change °C/s) from TAC and TDC codes ``tac``, ``tdc`` read at the evenly
    spaced instants ``t`` (s): the emulator's TAC relation (:func:`emulator.conversions.tac_to_celsius_per_s`) with
    TAC's resting level its mean before ``rest_before_s``, then a running mean over ``smoothing_s`` (whole windows
    only; each instant is its window's mean instant)."""
    t = np.asarray(t, float)
    rate = conv.tac_to_celsius_per_s(tac, tdc, np.mean(np.asarray(tac, float)[t < rest_before_s]))
    n = int(round(smoothing_s / np.median(np.diff(t))))
    window = np.ones(n) / n
    return np.convolve(t, window, mode="valid"), np.convolve(rate, window, mode="valid")


_ORDER = ("from k, ρ, c of each material (Incropera & DeWitt) through the thermal network; the contact "
          "conductance is a model choice, not tuned to the order")
#: what the TAC row measures, against SENSOR.md §4's statement
_TAC_RATE = ("§4: touching an object draws heat at a rate its thermal properties set, and TAC is the thermal flux "
             "(0–1 °C/s). The row orders the fastest cooling TAC reads during the 10 s hold. The thermistor lies "
             "under the skin and the fluid, so that rate peaks seconds after contact (peak_after_contact_s). That is "
             "far slower than TAC's 0.45 Hz high-pass (τ = 0.35 s), which differentiates such a ramp, so TAC reads "
             "it as a rate. " + _ORDER)


@claim_group("thermal")
def thermal_claims(b: Bench) -> list[Claim]:
    """Settled ~10 °C above ambient; TDC conversion, resolution and range read as codes over 0–70 °C; contact
    ordering by material."""
    p = b.params
    rest = b.acquire([], 2.0, sequence=("TDC",), slot_rate_Hz=100.0)
    settled = float(np.mean(conv.tdc_to_celsius(rest["TDC"][1])))
    # conversion, resolution and range, all read as TDC codes through the ADC at settled thermistor temperatures
    sweep = tdc_sweep(b)
    worst = max(abs(float(conv.tdc_to_celsius(code)) - bead) for bead, code in sweep)
    beads = np.array([x for x, _ in sweep])
    codes = np.array([c for _, c in sweep])
    overlaps = (np.maximum(beads[1:], beads[:-1]) >= 0.0) & (np.minimum(beads[1:], beads[:-1]) <= 70.0)
    codes_per_K = np.abs(np.diff(codes) / np.diff(beads))[overlaps]  # mean slope over each ~5 K step
    resolution = float(1.0 / codes_per_K.min())
    # range top: heat the settled thermistor past the last code (ambient 60 °C, heater rise 10..20 K) and find
    # where the mean code reaches 4094 from the last two unclipped points
    top = tdc_sweep(b, tuple((60.0, r) for r in np.arange(10.0, 20.01, 1.0)), offset=300)
    top_C = range_top_C(top)
    # touch and hold, 10 s, on each material at room temperature
    drops, tacs, tac_after_s = {}, {}, {}
    for k, m in enumerate(THERMAL_MATERIALS):
        t, tdc, tac = material_touch(b, m, seed_offset=k)
        temp = conv.tdc_to_celsius(tdc)
        before = temp[t < REST_BEFORE_S].mean()
        drops[m] = float(before - temp[(t > 10.9) & (t < 11.2)].mean())
        rate_t, rate = tac_rate_C_per_s(t, tac, tdc)
        tacs[m] = float(-np.min(rate))
        tac_after_s[m] = float(rate_t[np.argmin(rate)] - TOUCH_START_S)
    order_drop = all(drops[a] > drops[c] for a, c in zip(THERMAL_MATERIALS, THERMAL_MATERIALS[1:]))
    order_tac = all(tacs[a] > tacs[c] for a, c in zip(THERMAL_MATERIALS, THERMAL_MATERIALS[1:]))
    return [
        Claim("settled thermistor above ambient", "about 10 °C (± 1 K)", settled - p.ambient_temperature_C,
              9.0, 11.0, "K", "D ch. 4; §4", kind="consistency", note="reads back heater_rise_K = 10 K"),
        Claim("TDC conversion error over 0–70 °C", "≤ 0.1 °C", worst, 0.0, 0.1, "°C", "D eq. 4.4; §4",
              {"bead_C_and_mean_code": sweep}, kind="consistency",
              note="the thermistor and divider are built from the constants of the published conversion; read "
                   "as TDC codes through the ADC (noise on) at settled temperatures from 0 to 70 °C"),
        Claim("TDC resolution over 0–70 °C", "≤ 0.1 °C per code", resolution, 0.0, 0.1, "°C/code",
              "D Table 4-1; §4", kind="consistency",
              note="the smallest code step per kelvin between neighbouring settled temperatures, read as codes; "
                   "the divider is built from the published conversion's constants"),
        Claim("TDC range top (code 4094)", "≈ 74 °C (≥ 70 °C)", float(top_C), 70.0, 80.0, "°C", "D Table 4-1; §4",
              {"bead_C_and_mean_code": top}, kind="consistency",
              note="the settled thermistor heated past the top code (ambient 60 °C, heater rise 10–20 K), read as "
                   "codes; the temperature where the mean code reaches 4094, from the last two unclipped points; "
                   "the divider is built from the published conversion's constants"),
        Claim("TDC drop after 10 s: Al > glass > wood > foam", "strictly ordered", float(order_drop), 1.0, 1.0,
              "ordered", "D ch. 4; §4", {"drop_K": drops}, kind="prediction", note=_ORDER),
        Claim("TAC peak cooling rate over 10 s: Al > glass > wood > foam", "strictly ordered",
              float(order_tac), 1.0, 1.0, "ordered", "D ch. 4; §4",
              {"peak_cooling_C_per_s": tacs, "peak_after_contact_s": tac_after_s}, kind="prediction", note=_TAC_RATE),
        Claim("TDC drop on aluminum after 10 s", "a clear drop (> 0.5 K)", drops["aluminum"], 0.5, 10.0, "K",
              "D ch. 4 (model threshold)", kind="prediction",
              note="the 0.5 K threshold is the model's own; D gives no number"),
    ]

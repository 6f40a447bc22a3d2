"""Thermal claims: the thermistor settled about 10 °C above ambient, the TDC conversion (D eq. 4.4) and its
resolution and range, and cooling on contact ordered by the material's thermal properties."""

from __future__ import annotations

import numpy as np

from bench.verification.claims.core import Bench, Claim, claim_group
from emulator import conversions as conv
from emulator.stimuli import Touch
from emulator.thermal import tdc_volts, thermistor_ohm

THERMAL_MATERIALS = ("aluminum", "glass", "wood", "polystyrene foam")

_ORDER = ("from k, ρ, c of each material (Incropera & DeWitt) through the thermal network; the contact "
          "conductance is a model choice, not tuned to the order")


@claim_group("thermal")
def thermal_claims(b: Bench) -> list[Claim]:
    """Settled ~10 °C above ambient; TDC conversion within 0.1 °C over 0–70 °C; contact ordering by material."""
    p = b.params
    rest = b.acquire([], 2.0, sequence=("TDC",), slot_rate_Hz=100.0)
    settled = float(np.mean(conv.tdc_to_celsius(rest["TDC"][1])))
    # conversion: the emulator's TDC code for a known thermistor temperature, converted back (D eq. 4.4)
    worst = 0.0
    for t_true in np.arange(0.0, 70.01, 2.5):
        code = np.floor(float(tdc_volts(thermistor_ohm(t_true))) / conv.ADC_LSB_V + 0.5)
        worst = max(worst, abs(float(conv.tdc_to_celsius(code)) - t_true))
    codes = np.arange(1, 4095)
    temps = conv.tdc_to_celsius(codes)
    in_range = (temps >= 0) & (temps <= 70)
    resolution = float(np.max(np.abs(np.diff(temps[in_range]))))
    top = float(conv.tdc_to_celsius(4094))
    # touch and hold, 10 s, on each material at room temperature
    drops, tacs = {}, {}
    for k, m in enumerate(THERMAL_MATERIALS):
        touch = Touch(1.0, 1.0, 0.2, 10.0, electrode="E17", indenter_radius_mm=6.0, material=m)
        rec = b.acquire([touch], 11.5, sequence=("TDC", "TAC"), slot_rate_Hz=200.0, seed_offset=k)
        t, tdc = rec["TDC"]
        _, tac = rec["TAC"]
        temp = conv.tdc_to_celsius(tdc)
        before = temp[t < 0.9].mean()
        drops[m] = float(before - temp[(t > 10.9) & (t < 11.2)].mean())
        rate = conv.tac_to_celsius_per_s(tac, tdc, np.mean(tac[t < 0.9]))
        tacs[m] = float(-np.min(np.convolve(rate, np.ones(20) / 20, mode="valid")))
    order_drop = all(drops[a] > drops[c] for a, c in zip(THERMAL_MATERIALS, THERMAL_MATERIALS[1:]))
    order_tac = all(tacs[a] > tacs[c] for a, c in zip(THERMAL_MATERIALS, THERMAL_MATERIALS[1:]))
    return [
        Claim("settled thermistor above ambient", "about 10 °C (± 1 K)", settled - p.ambient_temperature_C,
              9.0, 11.0, "K", "D ch. 4; §4", kind="consistency", note="reads back heater_rise_K = 10 K"),
        Claim("TDC conversion error over 0–70 °C", "≤ 0.1 °C", worst, 0.0, 0.1, "°C", "D eq. 4.4; §4",
              kind="consistency",
              note="the thermistor and divider are built from the constants of the published conversion; "
                   "evaluated without SPI or ADC noise"),
        Claim("TDC resolution over 0–70 °C", "≤ 0.1 °C per code", resolution, 0.0, 0.1, "°C/code",
              "D Table 4-1; §4", kind="consistency", note="evaluates the published formula D eq. 4.4"),
        Claim("TDC range top (code 4094)", "≈ 74 °C (≥ 70 °C)", top, 70.0, 80.0, "°C", "D Table 4-1; §4",
              kind="consistency", note="evaluates the published formula D eq. 4.4"),
        Claim("TDC drop after 10 s: Al > glass > wood > foam", "strictly ordered", float(order_drop), 1.0, 1.0,
              "ordered", "D ch. 4; §4", {"drop_K": drops}, kind="prediction", note=_ORDER),
        Claim("TAC transient: Al > glass > wood > foam", "strictly ordered", float(order_tac), 1.0, 1.0, "ordered",
              "D ch. 4; §4", {"peak_cooling_C_per_s": tacs}, kind="prediction", note=_ORDER),
        Claim("TDC drop on aluminum after 10 s", "a clear drop (> 0.5 K)", drops["aluminum"], 0.5, 10.0, "K",
              "D ch. 4 (model threshold)", kind="prediction",
              note="the 0.5 K threshold is the model's own; D gives no number"),
    ]

"""Published conversions from ADC codes to physical units (SENSOR.md §2–§5).

These are the formulas a host applies; the emulator's physics must agree with
them (the claims check it).  Codes are 12-bit integers, 0..4095.
"""

from __future__ import annotations

import numpy as np

ADC_BITS = 12
ADC_FULL_SCALE_V = 3.3
ADC_CODES = 1 << ADC_BITS  # 4096
ADC_LSB_V = ADC_FULL_SCALE_V / ADC_CODES  # 0.806 mV

PDC_KPA_PER_BIT = 0.0365  # D Table 4-1, 36.5 Pa resolution
PAC_PA_PER_BIT = 0.37  # D Table 4-1
PDC_RANGE_KPA = (0.0, 100.0)
PAC_RANGE_PA = (-760.0, 760.0)
FORCE_N_PER_PDC_BIT = 0.0115  # D ch. 4, linear below 2 N, R^2 = 0.995


def pdc_to_kpa(code, offset):
    """Fluid pressure change in kPa from PDC codes relative to ``offset`` (codes at rest)."""
    return (np.asarray(code, float) - offset) * PDC_KPA_PER_BIT


def pac_to_pa(code, offset):
    """Vibration pressure in Pa from PAC codes relative to ``offset`` (mid-scale at rest)."""
    return (np.asarray(code, float) - offset) * PAC_PA_PER_BIT


def pdc_to_force_n(code, offset):
    """Contact force in N from the PDC rise above rest, valid below ~2 N."""
    return (np.asarray(code, float) - offset) * FORCE_N_PER_PDC_BIT


def tdc_to_celsius(code):
    """Thermistor temperature in °C from TDC codes (D eq. 4.4)."""
    x = np.clip(np.asarray(code, float), 1.0, ADC_CODES - 1) / 4095.0
    return 4025.0 / np.log((155183.0 - 46555.0 * x) / x) - 273.15


def tac_to_celsius_per_s(tac_code, tdc_code, tac_offset=2048.0, highpass_Hz=0.45, gain=98.0):
    """Rate of temperature change (°C/s) from TAC, given the TDC code at the same moment.

    D eq. 4.5 is garbled in the source; this is the emulator's relation.  TAC = 1.65 V + 98·HP(V_TDC) with
    a first-order high-pass at 0.45 Hz (τ = 1/(2π·0.45 Hz) = 0.354 s); for changes slower than τ,
    TAC − offset ≈ 98·τ·dV_TDC/dt, and dV_TDC/dT follows from the thermistor curve at the present TDC:
    dT/dt = (TAC − offset) / (98·τ·dTDC/dT).
    """
    tau = 1.0 / (2 * np.pi * highpass_Hz)
    tdc = np.asarray(tdc_code, float)
    h = 0.01  # °C
    t = tdc_to_celsius(tdc)
    slope = (celsius_to_tdc(t + h) - celsius_to_tdc(t - h)) / (2 * h)  # codes per °C (negative: NTC)
    return (np.asarray(tac_code, float) - tac_offset) / (gain * tau * slope)


def celsius_to_tdc(t_celsius):
    """Inverse of :func:`tdc_to_celsius` (as a real number of codes)."""
    e = np.exp(4025.0 / (np.asarray(t_celsius, float) + 273.15))
    return 4095.0 * 155183.0 / (e + 46555.0)


def impedance_ohm(code):
    """Electrode impedance in Ω from E_n codes (D eq. 4.1): (4095/E_n − 1)·10 kΩ."""
    e = np.clip(np.asarray(code, float), 1.0, None)
    return (4095.0 / e - 1.0) * 10e3

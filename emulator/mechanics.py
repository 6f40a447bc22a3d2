"""Fluid and skin: contact force and skin displacement -> fluid pressure at the transducer (SENSOR.md §1).

* Inflation sets the resting pressure (:class:`RestingPressure`).
* Contact force maps to DC pressure linearly (36.5 Pa per 11.5 mN) until the skin meets the core near
  2 N, where the slope falls (:func:`static_pressure_from_force`).  The skin/fluid system rings at
  ~330 Hz with a ~20 ms envelope, the resonance moving with inflation (:class:`ForceCoupling`).
* Skin displacement imposed by an actuator reaches the liquid through the same resonance plus a
  direct path through the incompressible liquid (a real zero, :class:`VibrationCoupling`).
"""

from __future__ import annotations

import numpy as np

from emulator import filters
from emulator.effects import Block, Effect
from emulator.params import SensorParams


def static_pressure_from_force(force_N, p: SensorParams):
    """DC pressure rise in Pa for a quasi-static contact force in N.

    Slope ``k`` below the knee, ``k·r`` above it, joined by a softplus of width ``w``:
    P = k·(F − (1 − r)·w·softplus((F − F_knee)/w)).  Negative forces (pulling) give no pressure change.
    """
    F = np.maximum(np.asarray(force_N, float), 0.0)
    k, r, w, Fk = p.force_to_pressure_Pa_per_N, p.force_slope_above_knee, p.force_knee_width_N, p.force_knee_N
    out = np.zeros_like(F)
    touching = F > 0  # most samples of a scene carry no force: skip the transcendental functions there
    x = (F[touching] - Fk) / w
    softplus = np.where(x > 30, x, np.log1p(np.exp(np.minimum(x, 30))))
    softplus0 = np.log1p(np.exp(-Fk / w))  # so that P(0) = 0
    out[touching] = k * (F[touching] - (1 - r) * w * (softplus - softplus0))
    return out if out.ndim else float(out)


def skin_resonance(params: SensorParams, fs: float, discretization: str, zero_hz: float | None = None):
    """The skin/fluid resonance at the present inflation (unit DC gain), optionally with a real zero."""
    z, p, k = filters.resonance(params.resonance_at_inflation_Hz, params.resonance_decay_s, zero_hz=zero_hz)
    return filters.SosFilter(filters.discretize(z, p, k, fs, discretization))


class RestingPressure(Effect):
    """Resting fluid pressure set by the inflation volume."""

    name = "resting_pressure"
    produces = ("fluid_pressure_Pa",)

    def __init__(self, params: SensorParams):
        self.value = params.resting_pressure_Pa

    def settle(self, inputs):
        return {"fluid_pressure_Pa": self.value}

    def process(self, block: Block, inputs):
        return {"fluid_pressure_Pa": np.full(block.n, self.value)}


class ForceCoupling(Effect):
    """Contact force -> fluid pressure: static force curve, then the skin/fluid resonance."""

    name = "force_coupling"
    consumes = ("contact_force_N",)
    produces = ("fluid_pressure_Pa",)
    passive = True

    def __init__(self, params: SensorParams, fs: float, discretization: str):
        self.params = params
        self.filter = skin_resonance(params, fs, discretization)

    def process(self, block: Block, inputs):
        static = static_pressure_from_force(inputs["contact_force_N"], self.params)
        return {"fluid_pressure_Pa": self.filter(static)}


class VibrationCoupling(Effect):
    """Skin displacement -> fluid pressure through the resonance and the direct liquid path."""

    name = "vibration_coupling"
    consumes = ("skin_displacement_m",)
    produces = ("fluid_pressure_Pa",)
    passive = True

    def __init__(self, params: SensorParams, fs: float, discretization: str):
        self.gain = params.displacement_to_pressure_Pa_per_m
        self.filter = skin_resonance(params, fs, discretization, zero_hz=params.displacement_zero_Hz)

    def process(self, block: Block, inputs):
        return {"fluid_pressure_Pa": self.gain * self.filter(inputs["skin_displacement_m"])}

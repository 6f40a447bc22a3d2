"""Fluid and skin: contact force and skin displacement -> fluid pressure at the transducer (SENSOR.md §1).

* Inflation sets the resting pressure (:class:`RestingPressure`) and, through the slope of that pressure–volume
  curve, the stiffness of the fluid seen through the skin.
* Contact mechanics (:func:`skin_fluid`): a contact indents the loaded skin area A by δ; the incompressible
  fluid must bulge the skin elsewhere by A·δ, so its pressure rises by dP/dV·A·δ and it carries the force
  k_f·δ with k_f = A²·dP/dV.  The skin shell carries the rest directly to the core and nail (stiffness k_s).
  The fluid pressure per N of contact is therefore φ/A with φ = k_f/(k_f + k_s): mN per PDC bit *follows*
  from geometry, inflation and the bridge + gain + ADC chain.  k_s is the one calibrated knob (11.5 mN/bit).
  The slope falls where the skin meets the core near 2 N (:func:`static_pressure_from_force`).
* Viscoelastic skin: the silicone's modulus relaxes (standard linear solid, ``skin_relaxation_time_s``,
  ``skin_relaxed_modulus_fraction``), so under a held force load moves from the skin to the fluid: PDC creeps
  up, and loading/unloading trace a loop (emulator/viscoelastic.py, exact update, state carried).
* Resonance: the skin membrane and the fluid layer under it (mass m) ring on the same stiffness
  k = k_f + k_s,0 (the unrelaxed skin at these frequencies): f = √(k/m)/2π.  The skin's areal mass is fixed by
  ``resonance_Hz`` at the nominal 0.5 mL (calibrated); how f moves with inflation is predicted (k_f ∝ dP/dV,
  fluid layer ∝ volume).  Damping: viscous shear in the fluid layer plus the skin's loss factor, the latter
  fixed by ``resonance_decay_s`` at 0.5 mL (calibrated); the decay's change with inflation is predicted.
* A fluid leak (a mechanical fault, :class:`FluidLeak`; D ch. 3: "the DC pressure component of the signal can be
  used to detect leakage") lowers the inflation volume with time: the resting pressure follows P(V) down, and a
  contact's share of the load that reaches the fluid, φ(V), and the pressure a skin displacement makes, k_f/A, fall
  with k_f ∝ dP/dV.  The resonance, its decay, the creep and the 2 N knee keep the run's starting inflation (the
  resonance moves by a few per cent over the first 0.1 mL lost).
* Skin displacement imposed by an actuator over the loaded area A pushes A·d of liquid, so the pressure
  rises by dP/dV·A·d = (k_f/A)·d — derived from inflation and geometry, like the force slope — through the
  same resonance plus a direct path through the incompressible liquid (a real zero, :class:`VibrationCoupling`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from emulator import filters
from emulator.effects import Block, Effect
from emulator.params import SensorParams
from emulator.viscoelastic import Creep

#: inflation at which ``resonance_Hz`` and ``resonance_decay_s`` are published (D ch. 4: ~0.5 cc)
NOMINAL_INFLATION_ML = 0.5
#: share of the fluid layer's mass that moves with the skin: linear velocity profile across the layer (the
#: fluid at the core wall is at rest), kinetic energy ∫(z/h)² = 1/3
FLUID_LAYER_MASS_SHARE = 1.0 / 3.0


@dataclass(frozen=True)
class SkinFluid:
    """Mechanical figures of the skin over the fluid at one inflation (SI units)."""

    fluid_stiffness_N_per_m: float  # k_f = A²·dP/dV
    skin_stiffness_relaxed_N_per_m: float  # k_s∞
    skin_stiffness_instant_N_per_m: float  # k_s0 = k_s∞ / (E∞/E0)
    pressure_per_N_relaxed: float  # Pa/N, quasi-static (held force)
    pressure_per_N_instant: float  # Pa/N, just after a step (and at the resonance)
    pressure_per_displacement_Pa_per_m: float  # k_f/A = A·dP/dV: skin pushed in by d over the loaded area
    creep_time_s: float  # retardation time of the pressure under a held force
    creep_ratio: float  # instantaneous / relaxed pressure
    layer_thickness_m: float  # fluid layer under the skin
    moving_mass_kg: float  # skin + the fluid moving with it
    skin_mass_kg: float
    resonance_Hz: float  # natural frequency √(k/m)/2π
    decay_s: float  # envelope time constant of the ringing
    fluid_damping_N_s_per_m: float
    skin_loss_factor: float
    implied_skin_thickness_m: float  # skin mass / (density × loaded area): a plausibility check, not an input


def _stiffness(p: SensorParams, volume_mL: float):
    """(k_f, dP/dV in Pa/m³) at an inflation volume in mL: slope of P = a·V^n times the loaded area squared."""
    dp_dv = p.resting_pressure_Pa_per_mL * p.resting_pressure_exponent * volume_mL ** (p.resting_pressure_exponent - 1)
    dp_dv *= 1e6  # per mL -> per m³
    return p.skin_load_area_m2**2 * dp_dv, dp_dv


def fluid_load_share(p: SensorParams, volume_mL):
    """φ = k_f/(k_f + k_s) (1, scalar or array): the share of a held contact force the fluid carries at an
    inflation volume (mL; the skin relaxed, as :func:`skin_fluid`'s ``pressure_per_N_relaxed`` = φ/A).  An empty
    finger (0 mL) has no fluid stiffness: the core carries everything."""
    kf = _stiffness(p, np.maximum(volume_mL, 0.0))[0]
    ks = p.skin_direct_stiffness_N_per_m
    if ks > 0.0:
        return kf / (kf + ks)
    return np.where(kf > 0.0, 1.0, 0.0)  # no skin stiffness: the fluid carries all it can, an empty finger nothing


def _fluid_mass_and_damping(p: SensorParams, volume_mL: float):
    """(moving fluid mass kg, viscous damping N·s/m, layer thickness m) of the layer under the loaded skin."""
    h = volume_mL * 1e-6 / p.fluid_wetted_area_m2
    mass = FLUID_LAYER_MASS_SHARE * p.fluid_density_kg_per_m3 * p.skin_load_area_m2 * h
    damping = p.fluid_viscosity_Pa_s * p.skin_load_area_m2 / h  # shear across the layer (Couette)
    return mass, damping, h


def skin_fluid(p: SensorParams) -> SkinFluid:
    """Contact mechanics, creep and resonance of the skin over the fluid at ``p.inflation_volume_mL``."""
    A = p.skin_load_area_m2
    rE = p.skin_relaxed_modulus_fraction
    ks_inf = p.skin_direct_stiffness_N_per_m
    ks_0 = ks_inf / rE

    def dynamics_at(volume_mL):
        kf, _ = _stiffness(p, volume_mL)
        m_f, c_f, h = _fluid_mass_and_damping(p, volume_mL)
        return kf + ks_0, m_f, c_f, h

    # anchor the skin's mass and loss factor at the nominal inflation (the published 330 Hz and 20 ms)
    k_n, mf_n, cf_n, _ = dynamics_at(NOMINAL_INFLATION_ML)
    w_n = 2 * math.pi * p.resonance_Hz
    m_total_n = k_n / w_n**2
    skin_mass = max(m_total_n - mf_n, 0.0)
    sigma_fluid_n = cf_n / (2 * (skin_mass + mf_n))
    # hysteretic skin loss: decay rate η·ω/2 (ζ = η/2); whatever the fluid does not supply
    eta = max(2.0 * (1.0 / p.resonance_decay_s - sigma_fluid_n) / w_n, 0.0)

    kf, _ = _stiffness(p, p.inflation_volume_mL)
    k, m_f, c_f, h = dynamics_at(p.inflation_volume_mL)
    m = skin_mass + m_f
    w = math.sqrt(k / m)
    decay = 1.0 / (c_f / (2 * m) + eta * w / 2)
    # creep of the pair (skin SLS ∥ elastic fluid path) under a held force: sls_retardation with the stiffnesses
    # written out, so that a vanishing skin stiffness (no creep) needs no division by it
    k_relaxed, k_instant = kf + ks_inf, kf + ks_0
    if k_relaxed > 0.0:
        tau, ratio = p.skin_relaxation_time_s * k_instant / k_relaxed, k_relaxed / k_instant
        phi_relaxed = kf / k_relaxed
    else:  # neither path stiff: the fluid takes the load as it comes
        tau, ratio, phi_relaxed = p.skin_relaxation_time_s, 1.0, 1.0
    out = SkinFluid(
        fluid_stiffness_N_per_m=kf, skin_stiffness_relaxed_N_per_m=ks_inf, skin_stiffness_instant_N_per_m=ks_0,
        pressure_per_N_relaxed=phi_relaxed / A, pressure_per_N_instant=phi_relaxed * ratio / A,
        pressure_per_displacement_Pa_per_m=kf / A,
        creep_time_s=tau, creep_ratio=ratio, layer_thickness_m=h, moving_mass_kg=m, skin_mass_kg=skin_mass,
        resonance_Hz=w / (2 * math.pi), decay_s=decay, fluid_damping_N_s_per_m=c_f, skin_loss_factor=eta,
        implied_skin_thickness_m=skin_mass / (p.skin_density_kg_per_m3 * A))
    return out


def hertz_contact(mass_kg: float, radius_m: float, speed_m_per_s: float, modulus_Pa: float):
    """Elastic Hertz impact of a rigid sphere on a half-space of plane-strain modulus E* (Pa).

    Returns (contact duration s, peak force N, peak indentation m):
    δ_max = (15·m·v²/(16·E*·√R))^(2/5), F_max = (4/3)·E*·√R·δ_max^(3/2), t_c ≈ 2.94·δ_max/v
    (= 2.87·(m²/(R·E*²·v))^(1/5)).
    """
    if min(mass_kg, radius_m, speed_m_per_s, modulus_Pa) <= 0:
        raise ValueError(f"hertz_contact: mass {mass_kg!r} kg, radius {radius_m!r} m, speed {speed_m_per_s!r} m/s "
                         f"and modulus {modulus_Pa!r} Pa must all be > 0")
    d_max = (15.0 * mass_kg * speed_m_per_s**2 / (16.0 * modulus_Pa * math.sqrt(radius_m))) ** 0.4
    f_max = 4.0 / 3.0 * modulus_Pa * math.sqrt(radius_m) * d_max**1.5
    return 2.9432 * d_max / speed_m_per_s, f_max, d_max


#: standard gravity (m/s²)
GRAVITY_M_PER_S2 = 9.80665
#: dry air at 20 °C and 101.325 kPa: density (kg/m³) and dynamic viscosity (Pa·s), for spheres falling onto the skin
AIR_DENSITY_KG_PER_M3 = 1.204
AIR_VISCOSITY_PA_S = 1.81e-5


def sphere_drag_coefficient(reynolds: float) -> float:
    """Drag coefficient of a smooth sphere at Reynolds number ``reynolds`` (Morrison 2013's fit to the standard
    curve, 0 < Re ≤ 10⁶; 24/Re, Stokes, as Re → 0)."""
    re = reynolds
    return (24.0 / re + 2.6 * (re / 5.0) / (1.0 + (re / 5.0) ** 1.52)
            + 0.411 * (re / 2.63e5) ** -7.94 / (1.0 + (re / 2.63e5) ** -8.0) + 0.25 * (re / 1e6) / (1.0 + re / 1e6))


@functools.lru_cache(maxsize=1024)
def fall_speed_m_per_s(mass_kg: float, radius_m: float, height_m: float,
                       air_density_kg_per_m3: float = AIR_DENSITY_KG_PER_M3,
                       air_viscosity_Pa_s: float = AIR_VISCOSITY_PA_S) -> float:
    """Speed (m/s) of a sphere released at rest after falling ``height_m`` through still air: weight less buoyancy
    against the sphere's drag (:func:`sphere_drag_coefficient`), so a small sphere approaches its terminal speed
    (a 0.25 mm solder ball about 4.3 m/s); √(2·g·h) in vacuum (``air_density_kg_per_m3`` = 0).  Integrated in
    height for u = v²: du/dh = 2·(g·(1 − ρ_air/ρ) − F_drag/m), with an implicit method (the light spheres' approach
    to their terminal speed is stiff)."""
    from scipy.integrate import solve_ivp

    if min(mass_kg, radius_m, height_m) <= 0 or air_density_kg_per_m3 < 0 or air_viscosity_Pa_s <= 0:
        raise ValueError(f"fall_speed_m_per_s: mass {mass_kg!r} kg, radius {radius_m!r} m and height {height_m!r} m "
                         f"must be > 0, air density {air_density_kg_per_m3!r} kg/m³ ≥ 0, viscosity > 0")
    if air_density_kg_per_m3 == 0:
        return math.sqrt(2.0 * GRAVITY_M_PER_S2 * height_m)
    density = mass_kg / (4.0 / 3.0 * math.pi * radius_m**3)
    if density <= air_density_kg_per_m3:
        raise ValueError(f"fall_speed_m_per_s: a sphere of {mass_kg!r} kg and radius {radius_m!r} m "
                         f"({density:.3g} kg/m³) does not fall through air")
    g_net = GRAVITY_M_PER_S2 * (1.0 - air_density_kg_per_m3 / density)
    area = math.pi * radius_m**2

    def du_dh(_h, u):
        v = math.sqrt(max(u[0], 0.0))
        if v == 0.0:
            return [2.0 * g_net]
        re = air_density_kg_per_m3 * v * 2.0 * radius_m / air_viscosity_Pa_s
        drag = 0.5 * air_density_kg_per_m3 * sphere_drag_coefficient(re) * area * v * v
        return [2.0 * (g_net - drag / mass_kg)]

    sol = solve_ivp(du_dh, (0.0, height_m), [0.0], method="LSODA", rtol=1e-9, atol=1e-12)
    if not sol.success:
        raise ArithmeticError(f"fall_speed_m_per_s: the fall did not integrate ({sol.message})")
    return math.sqrt(max(float(sol.y[0, -1]), 0.0))


def terminal_speed_m_per_s(mass_kg: float, radius_m: float, air_density_kg_per_m3: float = AIR_DENSITY_KG_PER_M3,
                           air_viscosity_Pa_s: float = AIR_VISCOSITY_PA_S) -> float:
    """Speed (m/s) at which a sphere's drag in still air equals its weight less buoyancy: what no fall exceeds."""
    from scipy.optimize import brentq

    density = mass_kg / (4.0 / 3.0 * math.pi * radius_m**3)
    weight = mass_kg * GRAVITY_M_PER_S2 * (1.0 - air_density_kg_per_m3 / density)

    def excess_drag(log_v):
        v = math.exp(log_v)
        re = air_density_kg_per_m3 * v * 2.0 * radius_m / air_viscosity_Pa_s
        return 0.5 * air_density_kg_per_m3 * sphere_drag_coefficient(re) * math.pi * radius_m**2 * v * v - weight

    return math.exp(brentq(excess_drag, math.log(1e-9), math.log(1e4), xtol=1e-12))


def static_pressure_from_force(force_N, p: SensorParams, slope_Pa_per_N: float | None = None):
    """DC pressure rise in Pa for a quasi-static contact force in N (default slope: the relaxed one).

    Slope ``k`` below the knee, ``k·r`` above it, joined by a softplus of width ``w``:
    P = k·(F − (1 − r)·w·softplus((F − F_knee)/w)).  Negative forces (pulling) give no pressure change.
    """
    F = np.maximum(np.asarray(force_N, float), 0.0)
    k = p.force_to_pressure_Pa_per_N if slope_Pa_per_N is None else slope_Pa_per_N
    r, w, Fk = p.force_slope_above_knee, p.force_knee_width_N, p.force_knee_N
    touching = F > 0  # most samples of a scene carry no force: skip the transcendental functions there
    every = bool(touching.all())  # ... and after a contact (the creep never quite returns to 0) none is idle
    Ft = F if every else F[touching]
    x = (Ft - Fk) / w
    if x.size and x.max() <= 30:  # softplus(x) = x beyond 30 (to double precision); below, log(1 + eˣ)
        softplus = np.log1p(np.exp(x))
    else:
        softplus = np.where(x > 30, x, np.log1p(np.exp(np.minimum(x, 30))))
    softplus0 = np.log1p(np.exp(-Fk / w))  # so that P(0) = 0
    pressure = k * (Ft - (1 - r) * w * (softplus - softplus0))
    if every:
        out = pressure
    else:
        out = np.zeros_like(F)
        out[touching] = pressure
    return out if out.ndim else float(out)


def skin_resonance(params: SensorParams, fs: float, discretization: str, zero_hz: float | None = None):
    """The skin/fluid resonance at the present inflation (unit DC gain), optionally with a real zero."""
    sf = skin_fluid(params)
    z, p, k = filters.resonance(sf.resonance_Hz, sf.decay_s, zero_hz=zero_hz)
    return filters.SosFilter(filters.discretize(z, p, k, fs, discretization))


@dataclass(frozen=True)
class FluidLeak:
    """Fluid leaving the finger (a mechanical fault: a worn seal or a punctured skin): the inflation volume falls
    by ``rate_mL_per_min`` from ``start_s`` (s) on, until the finger is empty."""

    rate_mL_per_min: float
    start_s: float = 0.0

    def __post_init__(self):
        for name, low in (("rate_mL_per_min", 0.0), ("start_s", 0.0)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < low:
                raise ValueError(f"fluid leak: {name} = {v!r}: must be a finite number ≥ {low:g}")

    def volume_mL(self, volume0_mL: float, t_s) -> np.ndarray:
        """The inflation volume (mL) at instants ``t_s`` (s) of a finger filled with ``volume0_mL``."""
        lost = self.rate_mL_per_min / 60.0 * np.maximum(np.asarray(t_s, float) - self.start_s, 0.0)
        return np.maximum(volume0_mL - lost, 0.0)

    def force_gain(self, p: SensorParams, t_s) -> np.ndarray:
        """How much of a contact's fluid pressure is left at instants ``t_s`` (1): φ(V(t)) / φ(V₀)."""
        v0 = p.inflation_volume_mL
        return fluid_load_share(p, self.volume_mL(v0, t_s)) / fluid_load_share(p, v0)

    def stiffness_gain(self, p: SensorParams, t_s) -> np.ndarray:
        """How much of the fluid stiffness k_f ∝ dP/dV is left at instants ``t_s`` (1): k_f(V(t)) / k_f(V₀), the
        pressure a skin displacement makes (:class:`VibrationCoupling`)."""
        v0 = p.inflation_volume_mL
        return _stiffness(p, self.volume_mL(v0, t_s))[0] / _stiffness(p, v0)[0]


class RestingPressure(Effect):
    """Resting fluid pressure set by the inflation volume (falling with a :class:`FluidLeak`)."""

    name = "resting_pressure"
    produces = ("fluid_pressure_Pa",)

    def __init__(self, params: SensorParams, leak: FluidLeak | None = None, start_s: float = 0.0):
        self.params, self.leak = params, leak
        self.value = params.resting_pressure_Pa
        # the sensor starts settled at the pressure of the fluid left by then (a leak may have begun before)
        self.start_value = self.value if leak is None else \
            float(params.resting_pressure_at(leak.volume_mL(params.inflation_volume_mL, start_s)))

    def settle(self, inputs):
        return {"fluid_pressure_Pa": self.start_value}

    def process(self, block: Block, inputs):
        if self.leak is None:
            return {"fluid_pressure_Pa": np.full(block.n, self.value)}
        volume = self.leak.volume_mL(self.params.inflation_volume_mL, block.times)
        return {"fluid_pressure_Pa": self.params.resting_pressure_at(volume)}


class ForceCoupling(Effect):
    """Contact force -> fluid pressure: skin creep, static force curve, then the skin/fluid resonance."""

    name = "force_coupling"
    consumes = ("contact_force_N",)
    produces = ("fluid_pressure_Pa",)
    passive = True

    def __init__(self, params: SensorParams, fs: float, discretization: str, leak: FluidLeak | None = None):
        self.params, self.leak = params, leak
        sf = skin_fluid(params)
        self.slope = sf.pressure_per_N_relaxed
        # the creep response r·F + (1 − r)·L[F] tends to F under a held force: the relaxed slope then applies
        self.creep = Creep.standard_linear_solid(sf.creep_time_s, sf.creep_ratio)
        self.filter = skin_resonance(params, fs, discretization)

    def process(self, block: Block, inputs):
        crept = self.creep.step(np.maximum(inputs["contact_force_N"], 0.0), block.fs)
        static = static_pressure_from_force(crept, self.params, self.slope)
        if self.leak is not None:  # less fluid carries less of the load
            static = static * self.leak.force_gain(self.params, block.times)
        return {"fluid_pressure_Pa": self.filter(static)}


class VibrationCoupling(Effect):
    """Skin displacement -> fluid pressure through the resonance and the direct liquid path."""

    name = "vibration_coupling"
    consumes = ("skin_displacement_m",)
    produces = ("fluid_pressure_Pa",)
    passive = True

    def __init__(self, params: SensorParams, fs: float, discretization: str, leak: FluidLeak | None = None):
        self.params, self.leak = params, leak
        self.gain = skin_fluid(params).pressure_per_displacement_Pa_per_m
        self.filter = skin_resonance(params, fs, discretization, zero_hz=params.displacement_zero_Hz)

    def process(self, block: Block, inputs):
        pressure = self.gain * self.filter(inputs["skin_displacement_m"])
        if self.leak is not None:  # less fluid, a softer fluid path: k_f/A per metre of skin pushed in
            pressure = pressure * self.leak.stiffness_gain(self.params, block.times)
        return {"fluid_pressure_Pa": pressure}

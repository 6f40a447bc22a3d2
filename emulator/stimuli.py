"""What happens to the finger: contact forces (taps, presses, sphere impacts) and imposed skin vibration.

Force stimuli are described by their cumulative impulse C(t) = ∫F dt, and reach
the grid as the exact mean force over the interval centred on each grid instant,
(C(t_n + Δt/2) − C(t_n − Δt/2))/Δt.  A sub-millisecond sphere impact therefore carries the same impulse
at 4.4 kHz as at 70 kHz, and no grid delays it (a one-sided interval would delay it by Δt/2).
Sphere impacts are Hertz contacts: the duration and pulse shape follow from the sphere's mass and radius,
the skin's modulus and the approach speed; the impulse is the momentum change m·v·(1 + e).
Displacement stimuli are smooth and are sampled at the grid instants.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from abc import ABC, abstractmethod
from dataclasses import KW_ONLY, dataclass

import numpy as np

from emulator.channels import ELECTRODE_COUNT
from emulator.effects import Block, Effect
from emulator.electrodes import CORE_RADIUS_MM, SKIN_BASE_X_MM
from emulator.mechanics import (AIR_DENSITY_KG_PER_M3, AIR_VISCOSITY_PA_S, GRAVITY_M_PER_S2, fall_speed_m_per_s,
                                hertz_contact)
from emulator.params import SensorParams

#: The spheres of D Table 5-2: name -> (mass kg, published impact energy J from 7 cm).
SPHERES: dict[str, tuple[float, float]] = {
    "0.25 mm solder ball": (0.072e-6, 0.049e-6),
    "0.45 mm solder ball": (0.422e-6, 0.289e-6),
    "1 mm aluminum bearing": (1.461e-6, 1.002e-6),
    "1 mm steel bearing": (4.089e-6, 2.805e-6),
    "3/64 in steel bearing": (6.902e-6, 4.734e-6),
    "5/64 in aluminum bearing": (11.415e-6, 7.830e-6),
}
DROP_HEIGHT_M = 0.07

#: densities of the spheres' materials (kg/m³): eutectic tin-lead solder, aluminium, bearing steel
MATERIAL_DENSITY_KG_PER_M3 = {"solder": 8400.0, "aluminum": 2700.0, "steel": 7850.0}


def sphere_density_kg_per_m3(name: str) -> float:
    """Density of a sphere of :data:`SPHERES` from the material its name gives."""
    for material, rho in MATERIAL_DENSITY_KG_PER_M3.items():
        if material in name.lower():
            return rho
    raise ValueError(f"sphere {name!r}: name none of the materials {', '.join(MATERIAL_DENSITY_KG_PER_M3)}")


def sphere_radius_m(mass_kg: float, density_kg_per_m3: float) -> float:
    """Radius of a solid sphere of this mass and density (m)."""
    return float((3.0 * mass_kg / (4.0 * np.pi * density_kg_per_m3)) ** (1.0 / 3.0))


#: name -> radius (m) from the published mass and the material's density (the names' diameters within 3 %)
SPHERE_RADII_M: dict[str, float] = {n: sphere_radius_m(m, sphere_density_kg_per_m3(n)) for n, (m, _) in SPHERES.items()}

_DEFAULTS = SensorParams()
#: plane-strain modulus E/(1 − ν²) of the skin a sphere lands on (Pa), for drops built without a sensor
SKIN_CONTACT_MODULUS_PA = _DEFAULTS.skin_youngs_modulus_Pa / (1.0 - _DEFAULTS.skin_poisson_ratio**2)


def _hertz_pulse_table(n: int = 4096):
    """Cumulative of sin^(3/2)(πx) over x in [0, 1], normalized to end at 1 (the Hertz force pulse shape)."""
    fine = 16
    x = np.linspace(0.0, 1.0, n * fine + 1)
    f = np.sin(np.pi * x) ** 1.5
    c = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(x))])
    return x[::fine], c[::fine] / c[-1], float(c[-1])


_HERTZ_X, _HERTZ_C, HERTZ_SHAPE_INTEGRAL = _hertz_pulse_table()


@dataclass(frozen=True)
class Limit:
    """What a stimulus field may hold: a finite number from ``lo`` (excluded if ``lo_open``) to ``hi``; None too
    if ``optional``.  These are physical limits (no negative duration or force); a scene file's tighter ranges
    are the scene validator's (bench.scenes.scene)."""

    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    optional: bool = False

    def allows(self, value) -> bool:
        if value is None:
            return self.optional
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
            return False
        return (value > self.lo if self.lo_open else value >= self.lo) and value <= self.hi

    def describe(self) -> str:
        text = "a finite number"
        if self.hi < math.inf:
            text += f" from {self.lo:g} to {self.hi:g}"
        elif self.lo > -math.inf:
            text += f" {'>' if self.lo_open else '≥'} {self.lo:g}"
        return text + (" or None" if self.optional else "")

    def or_none(self) -> "Limit":
        """The same range, None allowed too (an optional field)."""
        return dataclasses.replace(self, optional=True)


FINITE = Limit()
NON_NEGATIVE = Limit(0.0)
INSTANT_S = NON_NEGATIVE  # virtual time starts at 0
POSITIVE = Limit(0.0, lo_open=True)
CELSIUS = Limit(-273.15, lo_open=True)  # above absolute zero


class CheckedFields:
    """Checks the fields named in ``LIMITS`` (field -> :class:`Limit`) when a stimulus is made: a wrong value is a
    ValueError naming the stimulus, the field, the value and what is allowed (a NaN or negative force would
    otherwise produce nothing, silently)."""

    LIMITS: dict = {}

    def __post_init__(self):
        for name, limit in self.LIMITS.items():
            value = getattr(self, name)
            if not limit.allows(value):
                raise ValueError(f"{type(self).__name__}.{name} = {value!r}: must be {limit.describe()}")


class ForceStimulus(ABC):
    """A contact force on the skin over a finite time span [start_s, end_s]."""

    @abstractmethod
    def cumulative(self, t: np.ndarray) -> np.ndarray:
        """∫ F dt from −∞ to t, in N·s (closed form)."""

    def force(self, t: np.ndarray) -> np.ndarray:
        """Instantaneous force in N (for plots and checks)."""
        h = 1e-7
        return (self.cumulative(t + h) - self.cumulative(t - h)) / (2 * h)


#: the fields of a contact's place on the skin, optional for a press or a tap (None: no place, only the fluid feels
#: it): ``x_mm`` along the finger from the skin's clamp to the tip's apex, ``angle_deg`` around it from the ventral
#: midline, or over ``electrode``, pressed by an indenter of ``indenter_radius_mm``
PLACE_LIMITS = {"x_mm": Limit(SKIN_BASE_X_MM, CORE_RADIUS_MM, optional=True), "angle_deg": FINITE.or_none(),
                "indenter_radius_mm": POSITIVE}
#: the place of a contact given no x_mm or no angle_deg: the ventral pad (mm, °)
DEFAULT_X_MM, DEFAULT_ANGLE_DEG = -5.0, 0.0


def _check_place(s) -> None:
    """Refuse a place the stimulus ``s`` (a tap, press or touch) cannot have: an electrode that is no electrode's
    name, or, where the place is optional (a tap, a press), both an electrode and x_mm/angle_deg."""
    name = type(s).__name__
    most = max(ELECTRODE_COUNT.values())
    if s.electrode is not None and not (isinstance(s.electrode, str)
                                        and s.electrode in {f"E{k}" for k in range(1, most + 1)}):
        raise ValueError(f"{name}.electrode = {s.electrode!r}: an electrode's name, E1..E{most} (E20..E{most} on "
                         "a \"biotac-sp\"), or None for the place x_mm, angle_deg")
    if s.electrode is not None and not isinstance(s, Touch) and (s.x_mm is not None or s.angle_deg is not None):
        raise ValueError(f"{name}: give the place either as electrode ({s.electrode!r}) or as x_mm, angle_deg "
                         f"(x_mm = {s.x_mm!r}, angle_deg = {s.angle_deg!r}), not both")


def contact_place(s) -> tuple[str | None, float, float] | None:
    """Where a force stimulus ``s`` presses the skin: (electrode or None, x_mm, angle_deg), x_mm and angle_deg
    defaulting to the ventral pad's (−5 mm, 0°); None if it has no place (a press or tap given none, a sphere
    drop): then only the fluid feels it and the electrodes stay at rest."""
    if not isinstance(s, (Tap, Press)):
        return None
    if s.electrode is None and s.x_mm is None and s.angle_deg is None:
        return None
    return (s.electrode, DEFAULT_X_MM if s.x_mm is None else s.x_mm,
            DEFAULT_ANGLE_DEG if s.angle_deg is None else s.angle_deg)


@dataclass
class PlacedForce(CheckedFields, ForceStimulus):
    """A force stimulus optionally given a place on the skin, as keywords only (a subclass's own fields come first
    in its constructor): ``x_mm``/``angle_deg`` or ``electrode``, pressed by an indenter of ``indenter_radius_mm``
    (mm, °); no place: only the fluid feels it.  The fields' limits are :data:`PLACE_LIMITS`."""

    _: KW_ONLY
    x_mm: float | None = None
    angle_deg: float | None = None
    electrode: str | None = None
    indenter_radius_mm: float = 3.0

    def __post_init__(self):
        super().__post_init__()
        _check_place(self)


@dataclass
class Tap(PlacedForce):
    """A finger tap: raised-cosine force pulse of ``peak_N`` lasting ``duration_s`` from ``time_s``; optionally at
    a place (``x_mm``/``angle_deg`` or ``electrode``, ``indenter_radius_mm``: as a :class:`Touch`'s), where it
    dents the electrodes as a touch of that force would (no place: only the fluid feels it)."""

    LIMITS = {"time_s": INSTANT_S, "peak_N": NON_NEGATIVE, "duration_s": POSITIVE, **PLACE_LIMITS}
    time_s: float
    peak_N: float
    duration_s: float = 0.03

    @property
    def start_s(self):
        return self.time_s

    @property
    def end_s(self):
        return self.time_s + self.duration_s

    def cumulative(self, t):
        T = self.duration_s
        x = np.clip(np.asarray(t, float) - self.time_s, 0.0, T)
        return 0.5 * self.peak_N * (x - T / (2 * np.pi) * np.sin(2 * np.pi * x / T))

    def force(self, t):
        """Force in N: the raised cosine (F_peak/2)·(1 − cos(2π·x/T)) over x = t − time_s in [0, T], else 0."""
        T = self.duration_s
        x = np.asarray(t, float) - self.time_s
        inside = (x >= 0.0) & (x <= T)
        return np.where(inside, 0.5 * self.peak_N * (1.0 - np.cos(2 * np.pi * np.clip(x, 0.0, T) / T)), 0.0)


#: fewest steps of the electrodes' model a tap or a press given a place (a touch too) lasts, start to end: the model
#: samples its force at its rate (:attr:`emulator.fidelity.Fidelity.electrode_rate_Hz`), and over fewer the dent
#: depends on where the samples fall (measured on "fast", 250 Hz, E17 at 2 N: a 3 ms tap dents 0 or 297 codes, a
#: press of 1 ms ramps and no hold 0 or 410, and one of 3 ms ramps 228 to 410, as the start moves by 1 ms; at 8 ms,
#: the tap 355 to 410 and the press 352 to 410; a press of 1 ms ramps held 0.1 s dents 773 at any start)
PLACED_CONTACT_MIN_STEPS = 2


def placed_contact_too_short(s, electrode_rate_Hz: float) -> bool:
    """Whether ``s`` is a tap or a press (a touch too) given a place that lasts, start to end (a tap's duration_s,
    a press's 2·ramp_s + hold_s), under :data:`PLACED_CONTACT_MIN_STEPS` steps of the electrodes' model at
    ``electrode_rate_Hz`` (Hz)."""
    return contact_place(s) is not None and contact_span(s)[0] < PLACED_CONTACT_MIN_STEPS / electrode_rate_Hz


def contact_span(s) -> tuple[float, str]:
    """How long a tap or a press (a touch too) lasts, start to end (s), from its own fields (not end_s − start_s,
    which rounds with the start), and those fields as a message names them."""
    return (s.duration_s, "duration_s") if isinstance(s, Tap) else (2 * s.ramp_s + s.hold_s, "2·ramp_s + hold_s")


@dataclass
class SphereDrop(CheckedFields, ForceStimulus):
    """A sphere of ``mass_kg`` dropped from ``height_m`` through still air landing at ``time_s``: a Hertz impact.

    It lands at the speed the fall through air gives (:func:`emulator.mechanics.fall_speed_m_per_s`: within 5 % of
    √(2·g·h) from 7 cm, but a small sphere from higher nears its terminal speed); ``air_density_kg_per_m3`` = 0
    drops it in vacuum.

    The force pulse is F(t) ∝ sin^(3/2)(π·t/t_c) (Hertz: F ∝ δ^(3/2), δ ≈ δ_max·sin(π·t/t_c)) with the elastic
    Hertz duration t_c = 2.94·δ_max/v of a sphere of radius ``radius_m`` (default: from the mass and
    ``density_kg_per_m3``) on a skin of plane-strain modulus ``contact_modulus_Pa``; its area is the momentum
    change m·v·(1 + e).  Faster impacts are shorter (t_c ∝ v^(−1/5)), so the force spectrum depends on the
    speed.  ``contact_s`` (s), if given, replaces the Hertz pulse by a half-sine of that duration (legacy).
    """

    LIMITS = {"time_s": INSTANT_S, "mass_kg": POSITIVE, "height_m": POSITIVE, "restitution": Limit(0.0, 1.0),
              "contact_s": POSITIVE.or_none(), "radius_m": POSITIVE.or_none(),
              "density_kg_per_m3": POSITIVE, "contact_modulus_Pa": POSITIVE,
              "air_density_kg_per_m3": NON_NEGATIVE, "air_viscosity_Pa_s": POSITIVE}
    time_s: float
    mass_kg: float
    height_m: float = DROP_HEIGHT_M
    restitution: float = 0.3
    contact_s: float | None = None
    radius_m: float | None = None
    density_kg_per_m3: float = MATERIAL_DENSITY_KG_PER_M3["steel"]
    contact_modulus_Pa: float = SKIN_CONTACT_MODULUS_PA
    air_density_kg_per_m3: float = AIR_DENSITY_KG_PER_M3
    air_viscosity_Pa_s: float = AIR_VISCOSITY_PA_S

    @property
    def impact_speed_m_per_s(self) -> float:
        """Speed at impact after the fall through air (m/s)."""
        return fall_speed_m_per_s(self.mass_kg, self.sphere_radius_m, self.height_m, self.air_density_kg_per_m3,
                                  self.air_viscosity_Pa_s)

    @property
    def energy_J(self) -> float:
        """Potential energy m·g·h before the drop (J): D's "impact energy" (Table 5-2)."""
        return self.mass_kg * GRAVITY_M_PER_S2 * self.height_m

    @property
    def kinetic_energy_J(self) -> float:
        """Kinetic energy at impact ½·m·v² (J): less than :attr:`energy_J` by what the air took."""
        return 0.5 * self.mass_kg * self.impact_speed_m_per_s**2

    @property
    def momentum_Ns(self) -> float:
        """Momentum at impact m·v."""
        return self.mass_kg * self.impact_speed_m_per_s

    @property
    def impulse_Ns(self) -> float:
        """Momentum transferred: m·v·(1 + e)."""
        return self.mass_kg * self.impact_speed_m_per_s * (1.0 + self.restitution)

    @property
    def sphere_radius_m(self) -> float:
        return self.radius_m if self.radius_m is not None else sphere_radius_m(self.mass_kg, self.density_kg_per_m3)

    @property
    def contact_duration_s(self) -> float:
        """Hertz contact duration (or the given ``contact_s``)."""
        if self.contact_s is not None:
            return self.contact_s
        return hertz_contact(self.mass_kg, self.sphere_radius_m, self.impact_speed_m_per_s, self.contact_modulus_Pa)[0]

    @property
    def peak_force_N(self) -> float:
        """Largest force of the pulse (N)."""
        if self.contact_s is not None:
            return np.pi / 2 * self.impulse_Ns / self.contact_s
        return self.impulse_Ns / (self.contact_duration_s * HERTZ_SHAPE_INTEGRAL)

    @property
    def start_s(self):
        return self.time_s

    @property
    def end_s(self):
        return self.time_s + self.contact_duration_s

    def cumulative(self, t):
        tc = self.contact_duration_s
        x = np.clip((np.asarray(t, float) - self.time_s) / tc, 0.0, 1.0)
        if self.contact_s is not None:
            return 0.5 * self.impulse_Ns * (1.0 - np.cos(np.pi * x))
        return self.impulse_Ns * np.interp(x, _HERTZ_X, _HERTZ_C)


class OutsideModelWarning(UserWarning):
    """A stimulus a :class:`~emulator.sensor.Sensor` built in Python takes although the model does not hold for it
    (a scene file refuses it): its codes are the model's extrapolation, for analyses that probe it there."""


def drop_depth_problem(drop: SphereDrop, p: SensorParams) -> str | None:
    """Why a Hertz drop cannot be modelled on a sensor of parameters ``p`` (None if it can): at its deepest the
    sphere would push the skin through the fluid over the core (``resting_gap_mm``), where it meets the core and
    Hertz's contact on a deep soft layer no longer holds (a drop given ``contact_s`` is a legacy half-sine: taken)."""
    if drop.contact_s is not None:
        return None
    depth_m = hertz_contact(drop.mass_kg, drop.sphere_radius_m, drop.impact_speed_m_per_s, drop.contact_modulus_Pa)[2]
    if depth_m <= p.resting_gap_mm * 1e-3:
        return None
    return (f"a {drop.mass_kg * 1e6:g} mg sphere from {drop.height_m:g} m lands at "
            f"{drop.impact_speed_m_per_s:.3g} m/s and would indent the skin {depth_m * 1e3:.2f} mm, past the "
            f"{p.resting_gap_mm:g} mm of fluid over the core (resting_gap_mm), where the model's Hertz contact does "
            f"not hold: drop it from lower or drop a lighter sphere")


def sphere_drop_on(params: SensorParams, time_s: float, mass_kg: float, height_m: float = DROP_HEIGHT_M,
                   sphere: str | None = None, radius_m: float | None = None) -> SphereDrop:
    """A Hertz drop on a sensor: restitution and skin modulus from ``params``; the radius from ``radius_m``, else
    from the sphere's name in :data:`SPHERES` (its material's density), else from the mass as steel."""
    if radius_m is None and sphere is not None:
        radius_m = SPHERE_RADII_M[sphere]
    return SphereDrop(time_s, mass_kg, height_m, params.impact_restitution, radius_m=radius_m,
                      contact_modulus_Pa=params.skin_youngs_modulus_Pa / (1.0 - params.skin_poisson_ratio**2))


@dataclass
class Press(PlacedForce):
    """Press and hold: ramp to ``force_N`` over ``ramp_s``, hold ``hold_s``, ramp back down; optionally at a place
    (``x_mm``/``angle_deg`` or ``electrode``, ``indenter_radius_mm``), where it dents the electrodes exactly as a
    :class:`Touch` without shear or object (no place: only the fluid feels it)."""

    LIMITS = {"start": INSTANT_S, "force_N": NON_NEGATIVE, "ramp_s": POSITIVE, "hold_s": NON_NEGATIVE,
              **PLACE_LIMITS}
    start: float
    force_N: float
    ramp_s: float = 0.5
    hold_s: float = 1.0

    @property
    def start_s(self):
        return self.start

    @property
    def end_s(self):
        return self.start + 2 * self.ramp_s + self.hold_s

    def cumulative(self, t):
        F, r, h = self.force_N, self.ramp_s, self.hold_s
        x = np.clip(np.asarray(t, float) - self.start, 0.0, 2 * r + h)
        up = F * np.minimum(x, r) ** 2 / (2 * r)
        hold = F * np.clip(x - r, 0.0, h)
        d = np.clip(x - r - h, 0.0, r)
        down = F * (d - d**2 / (2 * r))
        return up + hold + down

    def force(self, t):
        """Normal force in N (piecewise linear: ramp, hold, ramp down)."""
        F, r, h = self.force_N, self.ramp_s, self.hold_s
        x = np.asarray(t, float) - self.start
        up = np.clip(x / r, 0, 1)
        down = np.clip((x - r - h) / r, 0, 1)
        return F * np.where(x < 0, 0.0, up - down)


@dataclass
class Touch(Press):
    """A contact at a place on the skin, with an object: the force profile of :class:`Press`, plus where
    (``x_mm`` along the finger, from the skin's clamp at −20 mm to the tip's apex at 5 mm, ``angle_deg`` around it
    from the ventral midline, or over ``electrode``),
    the indenter's radius, a tangential force (N at full normal force, at most :data:`TOUCH_STATIC_FRICTION` times
    it, in the skin's tangent plane at the place: ``shear_angle_deg`` 0° along the finger toward the tip — on the
    hemispherical tip along its meridian toward the apex — and 90° toward +angle) and, for thermal contact, the
    object's ``material`` and temperature."""

    LIMITS = {**Press.LIMITS, "x_mm": Limit(SKIN_BASE_X_MM, CORE_RADIUS_MM), "angle_deg": FINITE,
              "tangential_N": FINITE, "shear_angle_deg": FINITE, "object_temperature_C": CELSIUS.or_none()}
    _: KW_ONLY  # (as the place's fields: after start, force_N, ramp_s, hold_s, by keyword only)
    x_mm: float = DEFAULT_X_MM
    angle_deg: float = DEFAULT_ANGLE_DEG
    tangential_N: float = 0.0
    shear_angle_deg: float = 0.0
    material: str | None = None
    object_temperature_C: float | None = None

    def __post_init__(self):
        super().__post_init__()
        if self.object_temperature_C is not None and self.material is None:  # a scene refuses it too
            raise ValueError(f"Touch.object_temperature_C = {self.object_temperature_C!r} needs a material (e.g. "
                             f"material=\"aluminum\"): without one the touch exchanges no heat")


#: the largest static friction coefficient µs of the fingertip's silicone skin on any surface a touch may press
#: (1): the texture library's highest class, a dry silicone elastomer on an elastomer (1.3; rubber on rubber 1.16,
#: rubber on clean glass ≳ 1, Grosch 1963; fixtures/textures/library.toml's friction rules, whose 117 textures
#: span µs 0.26–1.2).  A touch sheared beyond µs·force_N would slip: that is a slide, not a touch.
TOUCH_STATIC_FRICTION = 1.3


def touch_slip_problem(touch: Touch) -> str | None:
    """Why a touch's ``tangential_N`` cannot be held (None if it can; the text follows the field and its value):
    beyond the static friction :data:`TOUCH_STATIC_FRICTION`·``force_N`` the skin would slip, which the touch's
    contact does not model."""
    limit_N = TOUCH_STATIC_FRICTION * touch.force_N
    if abs(touch.tangential_N) <= limit_N:
        return None
    return (f"exceeds the static friction µs·force_N = "
            f"{TOUCH_STATIC_FRICTION:g} × {touch.force_N!r} N = {limit_N:.3g} N (µs ≤ {TOUCH_STATIC_FRICTION:g}: "
            f"silicone skin on the grippiest surfaces, TOUCH_STATIC_FRICTION): a fingertip held so would slip; "
            f"lower the shear or raise force_N, or for a slipping contact use a slide (kind = \"slide\")")


@dataclass
class PowerOn(CheckedFields):
    """The sensor is powered at ``at_s``, from ambient temperature: the heaters start warming the core."""

    LIMITS = {"at_s": INSTANT_S}
    at_s: float = 0.0

    @property
    def start_s(self):
        return self.at_s

    end_s = start_s


@dataclass
class HeaterFailure(CheckedFields):
    """The heaters stop at ``at_s`` (a fault during a run): the core cools toward ambient over minutes."""

    LIMITS = {"at_s": INSTANT_S}
    at_s: float

    @property
    def start_s(self):
        return self.at_s

    end_s = start_s


@dataclass
class AmbientStep(CheckedFields):
    """The room temperature changes to ``temperature_C`` at ``at_s``."""

    LIMITS = {"at_s": INSTANT_S, "temperature_C": CELSIUS}
    at_s: float
    temperature_C: float

    @property
    def start_s(self):
        return self.at_s

    end_s = start_s


@dataclass
class Vibration(CheckedFields):
    """Sinusoidal skin displacement from a stiff actuator, optionally swept logarithmically.

    ``amplitude_m`` peak; frequency goes from ``f_start_Hz`` to ``f_stop_Hz`` over ``duration_s``;
    ``fade_s`` raised-cosine fades at both ends avoid clicks.
    """

    LIMITS = {"start_s": INSTANT_S, "duration_s": POSITIVE, "amplitude_m": NON_NEGATIVE, "f_start_Hz": POSITIVE,
              "f_stop_Hz": POSITIVE.or_none(), "fade_s": NON_NEGATIVE}
    start_s: float
    duration_s: float
    amplitude_m: float
    f_start_Hz: float
    f_stop_Hz: float | None = None
    fade_s: float = 0.01

    @property
    def end_s(self):
        return self.start_s + self.duration_s

    def frequency_at(self, t):
        f1 = self.f_stop_Hz or self.f_start_Hz
        x = np.clip((np.asarray(t, float) - self.start_s) / self.duration_s, 0, 1)
        return self.f_start_Hz * (f1 / self.f_start_Hz) ** x

    def value(self, t: np.ndarray) -> np.ndarray:
        """Skin displacement in m at instants ``t`` (s)."""
        t = np.asarray(t, float)
        tau = t - self.start_s
        f0, f1, T = self.f_start_Hz, (self.f_stop_Hz or self.f_start_Hz), self.duration_s
        if f1 == f0:
            phase = 2 * np.pi * f0 * tau
        else:
            k = np.log(f1 / f0) / T
            # the sweep exists only within [0, T] (the fade window is zero outside): evaluate its phase there only,
            # so a steep sweep never overflows far from it
            phase = 2 * np.pi * f0 * np.expm1(k * np.clip(tau, 0.0, T)) / k
        return self.amplitude_m * fade_window(tau, T, self.fade_s) * np.sin(phase)


def fade_window(tau: np.ndarray, duration_s: float, fade_s: float) -> np.ndarray:
    """Raised-cosine fade-in and fade-out of ``fade_s`` over [0, duration_s]; zero outside. ``tau`` in s."""
    inside = (tau >= 0) & (tau <= duration_s)
    if fade_s <= 0:
        return inside.astype(float)
    # clipped to [0, fade_s] before dividing (the same values): a fade of a few ulps (5e-324 s) overflowed to inf
    ramp = np.clip(np.minimum(tau, duration_s - tau), 0, fade_s) / fade_s
    return np.where(inside, 0.5 - 0.5 * np.cos(np.pi * ramp), 0.0)


def _overlapping(items, t_lo: float, t_hi: float):
    return [s for s in items if s.end_s >= t_lo and s.start_s <= t_hi]


class ContactForce(Effect):
    """Contact force on the skin from taps, presses and sphere impacts (mean over each sample)."""

    name = "contact_force"
    produces = ("contact_force_N",)

    def __init__(self, stimuli: list[ForceStimulus]):
        self.stimuli = sorted(stimuli, key=lambda s: s.start_s)

    def process(self, block: Block, inputs):
        dt = 1.0 / block.fs
        t_hi = block.times + 0.5 * dt
        t_lo = t_hi - dt
        out = np.zeros(block.n)
        for s in _overlapping(self.stimuli, t_lo[0], t_hi[-1]):
            # the interval mean is zero outside [start, end]: evaluate only the samples the stimulus touches
            a = int(np.searchsorted(t_hi, s.start_s, side="left"))
            b = int(np.searchsorted(t_lo, s.end_s, side="right"))
            if b > a:
                out[a:b] += (s.cumulative(t_hi[a:b]) - s.cumulative(t_lo[a:b])) / dt
        return {"contact_force_N": out}


class SampledStimuli(Effect):
    """Smooth stimuli sampled at the grid instants and summed into one signal."""

    def __init__(self, name: str, signal_name: str, stimuli: list, doc: str):
        self.name, self.produces, self.stimuli, self._doc = name, (signal_name,), stimuli, doc

    def describe(self) -> str:
        return self._doc

    def process(self, block: Block, inputs):
        t = block.times
        out = np.zeros(block.n)
        for s in _overlapping(self.stimuli, t[0], t[-1]):
            out += s.value(t)
        return {self.produces[0]: out}


def skin_displacement(stimuli: list[Vibration]) -> SampledStimuli:
    return SampledStimuli("skin_displacement", "skin_displacement_m", stimuli,
                          "skin displacement imposed by a vibration actuator (m)")


def calibration_pressure(stimuli: list["PressureCalibrator"]) -> SampledStimuli:
    return SampledStimuli("calibration_pressure", "fluid_pressure_Pa", stimuli,
                          "pressure applied directly to the liquid by a calibrator (Pa)")


@dataclass
class MountVibration(CheckedFields):
    """Random vibration reaching the liquid through the finger's mount from ``start_s`` on, such as a rig's stepper
    motor makes while it holds (D ch. 6: "even when locked in a fixed position, the stepper motor produced some
    background noise that was not consistent from trial to trial").

    White in fluid pressure, ``rms_Pa`` in the PAC band (10–1040 Hz: what PAC reads of it); its spectrum is an
    assumption (D gives none).  The samples come from the sensor's seed (:class:`emulator.extrinsic.MountNoise`)."""

    LIMITS = {"start_s": INSTANT_S, "rms_Pa": NON_NEGATIVE}
    start_s: float
    rms_Pa: float

    @property
    def end_s(self):
        return math.inf


@dataclass
class PressureCalibrator(CheckedFields):
    """A calibrated pressure applied straight to the liquid (bypassing the skin), as a lab calibrator would.

    ``offset_Pa`` plus an optional sinusoid of ``amplitude_Pa`` at ``frequency_Hz`` during
    [start_s, start_s + duration_s], with raised-cosine fades of ``fade_s``.
    """

    LIMITS = {"start_s": INSTANT_S, "duration_s": POSITIVE, "offset_Pa": FINITE, "amplitude_Pa": NON_NEGATIVE,
              "frequency_Hz": NON_NEGATIVE, "fade_s": NON_NEGATIVE}
    start_s: float
    duration_s: float
    offset_Pa: float = 0.0
    amplitude_Pa: float = 0.0
    frequency_Hz: float = 0.0
    fade_s: float = 0.01

    def __post_init__(self):
        super().__post_init__()
        if self.amplitude_Pa > 0 and self.frequency_Hz == 0:
            raise ValueError(f"PressureCalibrator.amplitude_Pa = {self.amplitude_Pa!r} needs frequency_Hz > 0 (the "
                             f"sinusoid's frequency: at 0 Hz it is zero); a steady pressure is offset_Pa")

    @property
    def end_s(self):
        return self.start_s + self.duration_s

    def value(self, t: np.ndarray) -> np.ndarray:
        """Pressure in Pa at instants ``t`` (s)."""
        tau = np.asarray(t, float) - self.start_s
        wave = self.offset_Pa + self.amplitude_Pa * np.sin(2 * np.pi * self.frequency_Hz * tau)
        return fade_window(tau, self.duration_s, self.fade_s) * wave


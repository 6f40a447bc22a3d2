"""Scene files: what happens to the finger, what the host reads, which noise, which fidelity, which seed.

A scene is a TOML file validated completely before anything runs; every problem is reported
with the file, the field (``stimulus[2].frequency_Hz``), the value and what is allowed.
See ``fixtures/scenes/`` for examples and ``biotac-bench run --help`` for the format.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

from bench import tomlfile
from bench.errors import SceneError, shortened
from bench.paths import folder_name_problem
from bench.scenes.limits import MAX_SEED, MAX_SENSORS, SPI_SIDES
from emulator.channels import ALL_CHANNEL_INDEX, CHANNEL_INDEX
from emulator.electrodes import CORE_RADIUS_MM, SKIN_BASE_X_MM, nail_touch_problem
from emulator.fidelity import PROFILES
from emulator.params import PARAMETER_FIELDS, SensorParams, check_parameter
from emulator.sensor import NoiseSources
from emulator.spi import protocol as proto
from emulator.stimuli import (DROP_HEIGHT_M, MATERIAL_DENSITY_KG_PER_M3, SPHERES, AmbientStep, HeaterFailure, PowerOn,
                              Press, PressureCalibrator, SphereDrop, Tap, Touch, Vibration, drop_depth_problem,
                              PLACED_CONTACT_MIN_STEPS, contact_place, contact_span, placed_contact_too_short,
                              sphere_drop_on, sphere_radius_m, touch_slip_problem)
from emulator.effects import effect_rng
from emulator.skin import Skin, contact_patch_area_m2
from emulator.sliding import Slide
from emulator.texture import SURFACE_LENGTH_M
from emulator.thermal import MATERIALS

MAX_DURATION_S = 36000.0
#: a mass_mg sphere drop's diameter_mm (mm) and the density it implies with the mass (kg/m³: from light plastics to
#: the densest metals), so that a mistyped unit is refused rather than dropped
SPHERE_DIAMETER_MM = (0.01, 50.0)
SPHERE_DENSITY_KG_PER_M3 = (500.0, 23000.0)
MAX_SCENE_BYTES = 1_000_000  # a scene file larger than 1 MB is refused before it is parsed
MAX_NESTING = 16  # arrays and tables nested deeper than this are refused (a scene needs 4 levels)
MAX_INSTANTS = 10_000  # instants of all stimuli together (each one is a stimulus the sensor computes)
TABLES = ("scene", "sensor", "host", "noise", "analysis", "faults", "skin")
#: keys of [sensor] and of each [[sensors]] table besides the parameters (``biotac-bench params``)
SENSOR_KEYS = ("unit", "variant")
#: D ch. 5's impact detection rule as ``bench.verification.analysis.DetectionRule`` applies it (more than
#: ``min_points`` PAC samples beyond 4σ within ``window_s`` of a drop); kept here because verification builds on
#: scenes, not the other way round — bench/tests/test_hostile_input.py holds the two equal.
IMPACT_RULE_MIN_POINTS, IMPACT_RULE_WINDOW_S = 3, 0.1


def sensor_seed(seed: int, k: int) -> int:
    """The noise seed of sensor ``k`` (1..5) of a scene, or of a pytest factory's call or session, whose seed is
    ``seed``: ``seed + k - 1`` (independent noise per sensor; sensor 1 draws ``seed`` itself).  The one convention of
    every route that numbers sensors: scenes (:meth:`Scene.for_sensor`, each sensor's slides) and the pytest plugin's
    factories (``bench.pytest_plugin.fixtures``)."""
    return seed + k - 1


def _r(v, limit: int = 80) -> str:
    """``v`` for messages as the scene file spells it, shortened when long (:func:`bench.tomlfile.spelled`)."""
    return tomlfile.spelled(v, limit)


def _cut(text: str, limit: int = 300) -> str:
    """A message from elsewhere, shortened when long (:func:`bench.errors.shortened`)."""
    return shortened(text, limit)


def _real(v) -> bool:
    """A number TOML can give (int or float, not bool) that is finite and fits a float."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    if isinstance(v, int):
        return abs(v) < 2 ** 1000
    return math.isfinite(v)


@dataclass
class Scene:
    name: str
    duration_s: float
    seed: int = 0
    fidelity: str = "default"
    description: str = ""
    params: SensorParams = field(default_factory=SensorParams)
    sequence: list[str] | str = "default"
    slot_rate_Hz: float = 4400.0
    spi_clock_Hz: float = proto.HOST_DEFAULT_CLOCK_HZ
    spi: str = "software"  # which implementation of the sensor's SPI side: "software" or "rtl"
    noise: NoiseSources = field(default_factory=NoiseSources)
    stimuli: list = field(default_factory=list)
    faults: dict = field(default_factory=dict)
    impact_detection: bool = False
    source: str = "<scene>"
    text: str = ""
    skin_before: dict = field(default_factory=dict)  # the skin's state before the first slide
    skin_after: dict = field(default_factory=dict)  # ... and after the last (Archard wear, if on)
    trial_skins: list = field(default_factory=list)  # the skin's state before each slide
    overrides: dict = field(default_factory=dict)  # values given on the command line, e.g. {"scene.seed": 5}
    unit: str = "nominal"  # sensor 1's unit: "nominal" or its seed (emulator.units)
    serial: str | None = None  # sensor 1's serial number (None: the unit's; "": none of its own, a twin)
    variant: str = "biotac"  # sensor 1's variant (emulator.channels.VARIANTS)
    #: sensors 2..N (declared in [[sensors]] or addressed by a stimulus), by number; sensor 1 is the scene itself
    sensors: dict = field(default_factory=dict)
    #: ``faults`` is sensor 1's, as ``params``, ``unit`` and ``stimuli`` are (the scene's [faults] and its own
    #: [sensor.faults]); ``common_faults`` the scene's [faults] alone, which sensors it does not describe have
    #: (None: the same as ``faults``, a scene built in code).  Sensors 2..N keep theirs in ``sensors``.
    common_faults: dict | None = None
    #: the texture library the slides came from: {"path", "sha256", "shipped"} (``[scene] library``, else the shipped
    #: one; None: no slide and no library named)
    library: dict | None = None

    def __post_init__(self):
        if self.serial is None:
            from emulator.units import serial_for

            self.serial = serial_for(None if self.unit == "nominal" else int(self.unit))
        if self.common_faults is None:
            self.common_faults = dict(self.faults)

    @property
    def n_sensors(self) -> int:
        """How many sensors the scene describes (1 + the highest of sensors 2..N)."""
        return max([1, *self.sensors])

    def sensor_spec(self, k: int) -> "SensorSpec":
        """Sensor ``k`` (1..N) of the scene; sensors the scene does not describe share sensor 1's unit,
        parameters and variant, feel nothing and have the faults every sensor has (with no serial of their own:
        the host sees the port's default)."""
        if k == 1:
            return SensorSpec(1, self.unit, self.serial, self.params, self.variant, list(self.stimuli),
                              self.skin_before, self.skin_after, list(self.trial_skins), dict(self.faults))
        if k in self.sensors:
            return self.sensors[k]
        return SensorSpec(k, self.unit, "", self.params, self.variant, [], {}, {}, [], dict(self.common_faults))

    def for_sensor(self, k: int) -> "Scene":
        """A one-sensor scene of sensor ``k``: its unit, parameters, variant, stimuli, skin and faults; the scene's
        host, noise, fidelity; seed :func:`sensor_seed` (``seed + k - 1``: independent noise per sensor)."""
        import dataclasses

        if k == 1 and not self.sensors:
            return self
        sp = self.sensor_spec(k)
        return dataclasses.replace(self, name=self.name if k == 1 else f"{self.name}-sensor{k}",
                                   seed=sensor_seed(self.seed, k), params=sp.params, stimuli=list(sp.stimuli),
                                   unit=sp.unit, serial=sp.serial, variant=sp.variant, sensors={},
                                   skin_before=sp.skin_before, skin_after=sp.skin_after,
                                   trial_skins=list(sp.trial_skins), faults=dict(sp.faults),
                                   common_faults=dict(sp.faults),
                                   impact_detection=self.impact_detection
                                   and any(isinstance(s, SphereDrop) for s in sp.stimuli))

    @property
    def channels(self) -> list[str]:
        """The channels sensor 1 answers: its variant's default frame (a BioTac SP's has E20..E24), or the host
        sequence's channels that its variant has — a 19-electrode sensor on a bus with a BioTac SP is asked for
        E20..E24 too and answers them with error words (0xA558); those had ended `run` and `validate` in a
        KeyError traceback."""
        from emulator.channels import variant

        v = variant(self.variant)
        seq = v.frame_names if self.sequence == "default" else self.sequence
        return sorted((n for n in set(seq) if n in v.channel_index), key=lambda n: v.channel_index[n])


@dataclass
class SensorSpec:
    """One sensor of a scene: number, unit ("nominal" or its seed), serial, parameters, variant, stimuli, skin,
    faults (the scene's [faults] and the sensor's own)."""

    index: int
    unit: str
    serial: str
    params: SensorParams
    variant: str
    stimuli: list
    skin_before: dict = field(default_factory=dict)
    skin_after: dict = field(default_factory=dict)
    trial_skins: list = field(default_factory=list)
    faults: dict = field(default_factory=dict)


class _Checker:
    """Collects problems while reading a table of values."""

    def __init__(self):
        self.problems: list[str] = []

    def number(self, table: dict, key: str, where: str, lo: float, hi: float, unit: str,
               default=None, required=False, integer=False):
        """``table[key]`` if it is a number within ``lo`` to ``hi``; ``default`` if the key is absent; None, with the
        problem noted, if the value is refused — never the default in its place, which later checks would take for
        the file's (a pressure's frequency_Hz = -5e-324 was read as the default 0 Hz, and its amplitude then refused
        for needing a frequency the file had given)."""
        note = unit[1:-1] if unit.startswith("(") and unit.endswith(")") else None  # what it is, not its unit
        if key not in table:
            if required:
                self.problems.append(f"{where}.{key} is missing ({(note or unit) + ', ' if unit else ''}{lo} to {hi})")
            return default
        v = table[key]
        kind = "a whole number" if integer else "a number"
        if isinstance(v, bool) or not isinstance(v, (int, float)) or (integer and not isinstance(v, int)):
            what = f" ({note}, {lo} to {hi})" if note else f"{' in ' + unit if unit else ''} ({lo} to {hi})"
            self.problems.append(f"{where}.{key} = {_r(v)}: must be {kind}{what}")
            return None
        if not _real(v) or not lo <= v <= hi:
            self.problems.append(f"{where}.{key} = {_r(v)}: allowed range is {lo} to {hi}{' ' + unit if unit else ''}")
            return None
        return v

    def times(self, table: dict, key: str, where: str, duration: float | None, required=True):
        if key not in table:
            if required:
                self.problems.append(f"{where}.{key} is missing (an instant in s, or a list of instants)")
            return []
        v = table[key]
        values = v if isinstance(v, list) else [v]
        if not values:
            self.problems.append(f"{where}.{key} = []: give at least one instant (s)")
        out = []
        for i, t in enumerate(values):
            name = f"{where}.{key}[{i}]" if isinstance(v, list) else f"{where}.{key}"
            if not _real(t) or t < 0:
                self.problems.append(f"{name} = {_r(t)}: must be an instant ≥ 0 s")
            elif duration is not None and t >= duration:
                self.problems.append(f"{name} = {_r(t)} s: after the end of the scene (duration_s = {duration})")
            else:
                out.append(float(t))
        return out

    def choice(self, table, key, where, choices, default=None, required=False):
        if key not in table:
            if required:
                self.problems.append(f"{where}.{key} is missing; one of: {', '.join(map(str, choices))}")
            return default
        v = table[key]
        if not isinstance(v, (str, int, float)) or isinstance(v, bool) or v not in choices:
            self.problems.append(f"{where}.{key} = {_r(v)}: must be one of: {', '.join(map(str, choices))}")
            return default
        return v

    def boolean(self, table, key, where, default):
        v = table.get(key, default)
        if not isinstance(v, bool):
            self.problems.append(f"{where}.{key} = {_r(v)}: must be true or false")
            return default
        return v

    def known_keys(self, table: dict, where: str, known):
        for k in table:
            if k not in known:
                self.problems.append(f"{where}: unknown field {_r(k)}; known fields: {', '.join(sorted(known))}")

    def table(self, data: dict, key: str, what: str) -> dict:
        """``data[key]`` if it is a table (missing: an empty one); otherwise a problem naming key and value."""
        v = data.get(key, {})
        if isinstance(v, dict):
            return v
        if isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            self.problems.append(f"{key} = {_r(v)}: must be one table ([{key}]), not an array of tables "
                                 f"([[{key}]]); {what}")
        else:
            self.problems.append(f"{key} = {_r(v)}: must be a table ([{key}]); {what}")
        return {}


#: ``textures`` of :func:`_slides` when the scene names no library: the shipped one, read only if a slide needs it
_SHIPPED = object()
#: where a touch presses, and optionally a tap or a press (then its electrodes feel it, as under a touch)
PLACE_FIELDS = ("x_mm", "angle_deg", "electrode", "indenter_radius_mm")
STIMULUS_KINDS = ("tap", "press", "touch", "sphere_drop", "vibration", "pressure", "power_on", "ambient_step",
                  "heater_failure", "slide", "replace_skin")
_STIMULUS_FIELDS = {
    "tap": {"kind", "at_s", "peak_N", "duration_s", *PLACE_FIELDS},
    "press": {"kind", "start_s", "force_N", "ramp_s", "hold_s", *PLACE_FIELDS},
    "sphere_drop": {"kind", "at_s", "sphere", "mass_mg", "height_m", "diameter_mm", "material"},
    "vibration": {"kind", "start_s", "duration_s", "amplitude_um", "frequency_Hz", "f_start_Hz", "f_stop_Hz", "fade_s"},
    "pressure": {"kind", "start_s", "duration_s", "offset_kPa", "amplitude_Pa", "frequency_Hz", "fade_s"},
    "touch": {"kind", "start_s", "force_N", "ramp_s", "hold_s", *PLACE_FIELDS, "tangential_N", "shear_angle_deg",
              "material", "object_temperature_C"},
    "power_on": {"kind", "at_s"},
    "ambient_step": {"kind", "at_s", "temperature_C"},
    "heater_failure": {"kind", "at_s"},
    "replace_skin": {"kind", "at_s"},
    "slide": {"kind", "start_s", "texture", "force_N", "velocity_mm_per_s", "distance_mm", "approach_s", "hold_s",
              "accel_s", "lift_s", "start_position_mm"},
}
for _fields in _STIMULUS_FIELDS.values():
    _fields.add("sensor")  # which sensor feels it (1..MAX_SENSORS; default 1)
SKIN_FIELDS = {"fingerprints", "ridge_height_um", "wear", "wear_coefficient"}
ELECTRODE_NAMES = tuple(f"E{n}" for n in range(1, 20))
SP_ELECTRODE_NAMES = tuple(f"E{n}" for n in range(20, 25))  # the BioTac SP's five more


def _stimuli(c: _Checker, items, duration, params: SensorParams, targets: list | None = None,
             params_of=None, variant_of=None, textures=_SHIPPED):
    """The stimuli of ``items``; ``targets`` (if given) receives the sensor number of each stimulus returned.
    ``params_of(k)``/``variant_of(k)``: sensor k's parameters and variant (default: ``params``, "biotac");
    ``textures``: the scene's texture library, as :func:`_slides` takes it."""
    first_once: dict = {}  # (kind, sensor) of power_on, heater_failure: which stimulus gave the one allowed
    out = []
    if not isinstance(items, list):
        c.problems.append(f"stimulus = {_r(items)}: stimulus must be an array of tables ([[stimulus]]), one per "
                          f"stimulus, each with a kind")
        return out
    for i, st in enumerate(items):
        w = f"stimulus[{i}]"
        if not isinstance(st, dict):
            c.problems.append(f"{w} = {_r(st)}: must be a table ([[stimulus]] with a kind: "
                              f"{', '.join(STIMULUS_KINDS)})")
            continue
        kind = c.choice(st, "kind", w, STIMULUS_KINDS, required=True)
        if kind is None:
            continue
        if kind == "sphere_drop":  # said why, rather than an unknown field
            for key in [f for f in PLACE_FIELDS if f in st]:
                c.problems.append(f"{w}.{key}: a sphere_drop has no place on the finger (the model gives its "
                                  f"sub-millisecond impulse to the fluid, PDC and PAC, not to the electrodes); for a "
                                  f"contact the electrodes feel, use a tap or a touch with x_mm + angle_deg or "
                                  f"electrode")
                st = {f: v for f, v in st.items() if f != key}
        c.known_keys(st, w, _STIMULUS_FIELDS[kind])
        k = c.number(st, "sensor", w, 1, MAX_SENSORS, "(a sensor number)", default=1, integer=True) or 1
        before = len(out)
        _one_stimulus(c, st, w, kind, k, duration, params_of(k) if params_of else params,
                      variant_of(k) if variant_of else "biotac", first_once, out, textures)
        if targets is not None:
            targets.extend([k] * (len(out) - before))
    return out


def _place(c: _Checker, st: dict, w: str, k: int, variant: str, params: SensorParams, optional: bool) -> dict:
    """The place fields (:data:`PLACE_FIELDS`) of a touch, or of a tap or press (``optional``: no place unless one
    is given, x_mm and angle_deg then None) on sensor ``k`` of ``variant``, for the stimulus's constructor; each
    problem (range, an electrode the finger lacks, the nail, two places, an indenter with no place) appended."""
    default_x, default_angle = (None, None) if optional else (-5.0, 0.0)
    place = dict(x_mm=c.number(st, "x_mm", w, SKIN_BASE_X_MM, CORE_RADIUS_MM, "mm", default=default_x),  # base clamp
                 angle_deg=c.number(st, "angle_deg", w, -180.0, 180.0, "°", default=default_angle),  # to tip apex
                 indenter_radius_mm=c.number(st, "indenter_radius_mm", w, 0.1, 15.0, "mm", default=3.0))
    names = ELECTRODE_NAMES + (SP_ELECTRODE_NAMES if variant == "biotac-sp" else ())
    if st.get("electrode") in SP_ELECTRODE_NAMES and variant != "biotac-sp":
        c.problems.append(f"{w}.electrode = {_r(st['electrode'])}: sensor {k} is a {_r(variant)}, which has "
                          f"E1..E19; E20..E24 are on a \"biotac-sp\" ([sensor] or [[sensors]] variant)")
    place["electrode"] = c.choice(st, "electrode", w, names) if st.get("electrode") not in SP_ELECTRODE_NAMES \
        or variant == "biotac-sp" else None
    if (problem := nail_touch_problem(place["angle_deg"], params)) is not None:
        c.problems.append(f"{w}.angle_deg = {_r(st['angle_deg'])}: {problem}")
    where = [k for k in ("x_mm", "angle_deg") if k in st]
    if "electrode" in st and where:
        c.problems.append(f"{w}: give the place either as electrode ({_r(st['electrode'])}) or as x_mm + "
                          f"angle_deg ({', '.join(f'{k} = {_r(st[k])}' for k in where)}), not both")
        if optional:  # (refused; the stimulus made for the span check takes the x_mm/angle_deg place)
            place["electrode"] = None
    if optional and "indenter_radius_mm" in st and not ("electrode" in st or where):
        c.problems.append(f"{w}.indenter_radius_mm: the indenter of a place: give x_mm + angle_deg or electrode "
                          f"too (without a place only the fluid feels a {st.get('kind')}, no electrode)")
    if place["indenter_radius_mm"] is None:  # (out of range: a problem already; no stimulus is made of it)
        place["indenter_radius_mm"] = 3.0
    return place


def _one_stimulus(c: _Checker, st: dict, w: str, kind: str, k: int, duration, params: SensorParams,
                  variant: str, first_once: dict, out: list, textures=_SHIPPED) -> None:
    """Append the stimuli of one [[stimulus]] table (for sensor ``k``) to ``out`` (``textures``: as for
    :func:`_slides`)."""
    if kind == "tap":
        peak = c.number(st, "peak_N", w, 0.0, 50.0, "N", required=True)
        dur = c.number(st, "duration_s", w, 1e-3, 10.0, "s", default=0.03)
        place = _place(c, st, w, k, variant, params, optional=True)
        if dur is not None:  # its span is checked whatever its force (a bad peak_N is a problem of its own)
            taps = [Tap(t, 0.0 if peak is None else peak, dur, **place) for t in c.times(st, "at_s", w, duration)]
            out += _valid(peak is not None, _ending_in_scene(c, w, "tap", taps, duration))
    elif kind == "press":
        start = c.times(st, "start_s", w, duration)
        force = c.number(st, "force_N", w, 0.0, 50.0, "N", required=True)
        ramp = c.number(st, "ramp_s", w, 1e-3, 3600.0, "s", default=0.5)
        hold = c.number(st, "hold_s", w, 0.0, 36000.0, "s", default=1.0)
        place = _place(c, st, w, k, variant, params, optional=True)
        if None not in (ramp, hold):
            presses = [Press(t, 0.0 if force is None else force, ramp, hold, **place) for t in start]
            out += _valid(force is not None, _ending_in_scene(c, w, "press", presses, duration))
    elif kind == "sphere_drop":
        # a Hertz impact on this sensor's skin (emulator.stimuli.sphere_drop_on): a named sphere gives its mass and
        # radius; a mass_mg drop its radius from diameter_mm, or from its material's density (default steel)
        height = c.number(st, "height_m", w, 1e-3, 10.0, "m", default=DROP_HEIGHT_M)
        if "sphere" in st and "mass_mg" in st:
            c.problems.append(f"{w}: give either sphere or mass_mg, not both")
        name, radius, ok = None, None, True
        if "mass_mg" in st:
            mass_mg = c.number(st, "mass_mg", w, 1e-4, 1e4, "mg")
            mass = None if mass_mg is None else mass_mg / 1e6
            if "diameter_mm" in st and "material" in st:
                c.problems.append(f"{w}: give diameter_mm or material for a mass_mg drop, not both (the material's "
                                  f"density and the mass give the diameter)")
                ok = False
            elif "diameter_mm" in st:
                d_mm = c.number(st, "diameter_mm", w, SPHERE_DIAMETER_MM[0], SPHERE_DIAMETER_MM[1], "mm")
                ok = d_mm is not None
                if ok and mass is not None:
                    radius = d_mm / 2e3
                    rho = mass / (4.0 / 3.0 * math.pi * radius**3)
                    lo, hi = SPHERE_DENSITY_KG_PER_M3
                    if not lo <= rho <= hi:
                        c.problems.append(f"{w}: mass_mg = {_r(mass_mg)} and diameter_mm = {_r(d_mm)} make a sphere "
                                          f"of density {rho:.4g} kg/m³; allowed range is {lo:g} to {hi:g} kg/m³ "
                                          f"(steel 7850)")
                        ok = False
            elif "material" in st:
                material = c.choice(st, "material", w, tuple(MATERIAL_DENSITY_KG_PER_M3))
                ok = material is not None
                if ok and mass is not None:
                    radius = sphere_radius_m(mass, MATERIAL_DENSITY_KG_PER_M3[material])
        else:
            for key in ("diameter_mm", "material"):
                if key in st:
                    c.problems.append(f"{w}.{key}: only with mass_mg (a named sphere has its own "
                                      f"{'diameter' if key == 'diameter_mm' else 'material'})")
                    ok = False
            name = c.choice(st, "sphere", w, tuple(SPHERES), required=True)
            mass = None if name is None else SPHERES[name][0]
        for t in c.times(st, "at_s", w, duration):
            if mass is not None and height is not None and ok:
                drop = sphere_drop_on(params, t, mass, height, sphere=name, radius_m=radius)
                if (problem := drop_depth_problem(drop, params)) is not None:
                    c.problems.append(f"{w}: {problem}")
                    break
                out.append(drop)
    elif kind == "vibration":
        start = c.times(st, "start_s", w, duration)
        dur = c.number(st, "duration_s", w, 1e-3, MAX_DURATION_S, "s", required=True)
        amp = c.number(st, "amplitude_um", w, 0.0, 1000.0, "µm", required=True)
        fade = c.number(st, "fade_s", w, 0.0, 10.0, "s", default=0.01)
        if "fade_s" not in st and dur is not None:  # the default fade fits a short stimulus: it reaches its amplitude
            fade = min(fade, dur / 2)
        if "frequency_Hz" in st:
            f0 = c.number(st, "frequency_Hz", w, 1.0, 3000.0, "Hz")
            f1 = None
            if "f_start_Hz" in st or "f_stop_Hz" in st:
                c.problems.append(f"{w}: give frequency_Hz for a tone or f_start_Hz and f_stop_Hz for a sweep")
        else:
            f0 = c.number(st, "f_start_Hz", w, 1.0, 3000.0, "Hz", required=True)
            f1 = c.number(st, "f_stop_Hz", w, 1.0, 3000.0, "Hz", required=True)
        if None not in (dur, fade) and _fade_fits(c, st, w, dur, fade):
            given = None not in (amp, f0) and (f1 is not None or "frequency_Hz" in st)
            what = "vibration" if not given or f1 is None else f"vibration (a {f0:g} → {f1:g} Hz sweep)"
            vibrations = [Vibration(t, dur, amp / 1e6, f0, f1, fade) if given else Vibration(t, dur, 0.0, 1.0,
                                                                                            fade_s=fade)
                          for t in start]
            out += _valid(given, _ending_in_scene(c, w, what, vibrations, duration))
    elif kind == "pressure":
        start = c.times(st, "start_s", w, duration)
        dur = c.number(st, "duration_s", w, 1e-3, MAX_DURATION_S, "s", required=True)
        offset = c.number(st, "offset_kPa", w, -100.0, 200.0, "kPa", default=0.0)
        amp = c.number(st, "amplitude_Pa", w, 0.0, 1e5, "Pa", default=0.0)
        freq = c.number(st, "frequency_Hz", w, 0.0, 3000.0, "Hz", default=0.0)
        fade = c.number(st, "fade_s", w, 0.0, 10.0, "s", default=0.01)
        if "fade_s" not in st and dur is not None:  # the default fade fits a short stimulus: it reaches its amplitude
            fade = min(fade, dur / 2)
        if amp is not None and freq is not None and amp > 0 and freq == 0:
            c.problems.append(f"{w}: amplitude_Pa = {amp:g} needs frequency_Hz > 0 (the sinusoid's frequency: at 0 Hz "
                              f"it is zero); a steady pressure is offset_kPa")
            amp = None
        if None not in (dur, fade) and _fade_fits(c, st, w, dur, fade):
            given = None not in (offset, amp, freq)
            calibrators = [PressureCalibrator(t, dur, offset * 1e3, amp, freq, fade) if given else
                           PressureCalibrator(t, dur, fade_s=fade) for t in start]
            out += _valid(given, _ending_in_scene(c, w, "pressure", calibrators, duration))
    elif kind == "touch":
        start = c.times(st, "start_s", w, duration)
        place = _place(c, st, w, k, variant, params, optional=False)
        electrode = place.pop("electrode")
        vals = dict(
            force_N=c.number(st, "force_N", w, 0.0, 50.0, "N", required=True),
            ramp_s=c.number(st, "ramp_s", w, 1e-3, 3600.0, "s", default=0.5),
            hold_s=c.number(st, "hold_s", w, 0.0, 36000.0, "s", default=1.0),
            **place,
            tangential_N=c.number(st, "tangential_N", w, -20.0, 20.0, "N", default=0.0),
            shear_angle_deg=c.number(st, "shear_angle_deg", w, -180.0, 180.0, "°", default=0.0),
            object_temperature_C=c.number(st, "object_temperature_C", w, -40.0, 120.0, "°C"),
        )
        mat = c.choice(st, "material", w, tuple(MATERIALS))
        if None not in (vals["force_N"], vals["tangential_N"]):  # a shear the skin holds without slipping
            probe = Touch(0.0, vals["force_N"], tangential_N=vals["tangential_N"])
            if (problem := touch_slip_problem(probe)) is not None:
                c.problems.append(f"{w}.tangential_N = {_r(st['tangential_N'])}: {problem}")
        if "object_temperature_C" in st and "material" not in st:
            c.problems.append(f"{w}.object_temperature_C = {_r(st['object_temperature_C'])}: an object "
                              f"temperature needs a material for the thermal contact (e.g. \"aluminum\")")
        if mat is None:  # none given, or not a material (each a problem already): a Touch refuses the temperature
            vals["object_temperature_C"] = None
        if None not in (vals["ramp_s"], vals["hold_s"]):
            given = None not in [v for k, v in vals.items() if k != "object_temperature_C"]
            span = {k: vals[k] for k in ("ramp_s", "hold_s")}
            touches = [Touch(t, electrode=electrode, material=mat, **vals) if given else Touch(t, 0.0, **span)
                       for t in start]
            out += _valid(given, _ending_in_scene(c, w, "touch", touches, duration))
    elif kind in ("power_on", "heater_failure"):
        at = c.times(st, "at_s", w, duration)
        what = ("the sensor is powered on once (heaters start from ambient)" if kind == "power_on" else
                "the heaters fail once (they stay off)")
        if len(at) > 1:
            c.problems.append(f"{w}.at_s = {_r(st['at_s'])}: {kind} happens at most once per "
                              f"{'scene' if k == 1 else 'sensor'}: {what}")
        elif at:
            if first_once.get((kind, k)):
                c.problems.append(f"{w}: a second {kind} (the first is {first_once[kind, k]})"
                                  f"{f' on sensor {k}' if k != 1 else ''}: {what}")
            else:
                first_once[kind, k] = w
                out.append((PowerOn if kind == "power_on" else HeaterFailure)(at[0]))
    elif kind == "ambient_step":
        at = c.times(st, "at_s", w, duration)
        temp = c.number(st, "temperature_C", w, -20.0, 60.0, "°C", required=True)
        if temp is not None:
            out += [AmbientStep(t, temp) for t in at]
    elif kind == "slide":
        out += _slides(c, st, w, duration, textures)
    elif kind == "replace_skin":
        out += [SkinReplacement(t) for t in c.times(st, "at_s", w, duration)]


def _slides(c: _Checker, st: dict, w: str, duration, textures=_SHIPPED) -> list[SlideSpec]:
    """One :class:`SlideSpec` per start instant (a list of ``start_s`` is a list of trials).  ``textures``: the
    scene's own library (a :class:`~bench.textures.library.LibraryFile`), :data:`_SHIPPED` (the shipped library),
    or None (the scene's library could not be read: that is its problem, and the texture is not looked up)."""
    from bench.errors import TextureError
    from bench.textures.library import texture as find_texture

    starts = c.times(st, "start_s", w, duration)
    vals = dict(
        force_N=c.number(st, "force_N", w, 0.01, 20.0, "N", required=True),
        velocity_mm_per_s=c.number(st, "velocity_mm_per_s", w, 0.1, 500.0, "mm/s", required=True),
        distance_mm=c.number(st, "distance_mm", w, 0.1, 500.0, "mm", required=True),
        approach_s=c.number(st, "approach_s", w, 0.005, 60.0, "s", default=0.3),
        hold_s=c.number(st, "hold_s", w, 0.0, 600.0, "s", default=0.5),
        accel_s=c.number(st, "accel_s", w, 0.001, 10.0, "s", default=0.05),
        lift_s=c.number(st, "lift_s", w, 0.005, 60.0, "s", default=0.2),
        start_position_mm=c.number(st, "start_position_mm", w, 0.0, 1000.0, "mm"),
    )
    tex = None
    if "texture" not in st:
        c.problems.append(f"{w}.texture is missing: a library texture by number (30, \"T30\") or name")
    elif textures is not None:
        own = textures is not _SHIPPED
        try:
            tex = textures.texture(st["texture"]) if own else find_texture(st["texture"])
        except TextureError as e:
            c.problems.append(f"{w}.texture = {_r(st['texture'])}: " + "; ".join(_cut(p) for p in e.problems)
                              + (f" (the scene's library, scene.library: {_cut(textures.path)})" if own else ""))
    timing = ("velocity_mm_per_s", "distance_mm", "approach_s", "hold_s", "accel_s", "lift_s")
    if None in [vals[k] for k in timing]:
        return []
    v, d, a = vals["velocity_mm_per_s"] / 1e3, vals["distance_mm"] / 1e3, vals["accel_s"]
    if d < v * a:
        c.problems.append(f"{w}.distance_mm = {_r(vals['distance_mm'])}: shorter than the stage's acceleration and "
                          f"braking at this velocity ({v * a * 1e3:.3g} mm); lower accel_s or slide farther")
        return []
    # its span is checked whatever its texture and force (a bad one is a problem of its own)
    start_m = None if vals["start_position_mm"] is None else vals["start_position_mm"] / 1e3
    force = 0.0 if vals["force_N"] is None else vals["force_N"]
    slides = [SlideSpec(t, tex, force, v, d, vals["approach_s"], vals["hold_s"], a, vals["lift_s"], start_m, where=w)
              for t in starts]
    return _valid(tex is not None and vals["force_N"] is not None, _ending_in_scene(c, w, "slide", slides, duration))


#: how far (s) a stimulus may end past the scene's end for float rounding (e.g. 0.1 + 2·0.2 + 0.3 s in a 0.6 s scene)
END_TOLERANCE_S = 1e-9


def _valid(given: bool, stimuli: list) -> list:
    """``stimuli`` if their values were ``given`` validly, else none: a stimulus with a bad value still has its span
    checked (with placeholder values), so that every problem of a [[stimulus]] is reported at once."""
    return stimuli if given else []


def _fade_fits(c, st: dict, w: str, dur, fade) -> bool:
    """A fade-in and a fade-out of ``fade`` s each must fit in the stimulus's ``dur`` s: a longer fade never lets the
    stimulus reach its amplitude (a 5 s fade on a 0.5 s vibration reached 0.6 % of it), so a given one is refused
    (the default 0.01 s is shortened to ``dur`` / 2 by the caller)."""
    if dur is not None and fade is not None and fade > dur / 2 and "fade_s" in st:
        c.problems.append(f"{w}.fade_s = {fade:g}: the fade-in and fade-out must fit in duration_s = {dur:g} s "
                          f"(fade_s at most {dur / 2:g} s), or the stimulus never reaches its amplitude")
        return False
    return True


def _ending_in_scene(c: _Checker, w: str, what: str, stimuli: list, duration) -> list:
    """The ``stimuli`` (each with ``start_s`` and ``end_s`` in s) that end by the scene's end (``duration`` in s);
    a problem naming ``w``, ``what``, the start, the end and duration_s for each that ends after it, which the
    run would silently cut off."""
    kept = []
    for s in stimuli:
        if duration is not None and s.end_s > duration + END_TOLERANCE_S:
            c.problems.append(f"{w}: the {what} starting at {s.start_s} s ends at {s.end_s:.3f} s, after the end of "
                              f"the scene (duration_s = {duration}); start it earlier, shorten it or lengthen the "
                              f"scene")
        else:
            kept.append(s)
    return kept


@dataclass
class SlideSpec:
    """A slide as the scene file gives it (SI units); :func:`build_slides` turns the scene's slides into
    :class:`emulator.sliding.Slide` stimuli on one skin that wears from trial to trial."""

    start_s: float
    texture: object
    force_N: float
    velocity_m_per_s: float
    distance_m: float
    approach_s: float
    hold_s: float
    accel_s: float
    lift_s: float
    start_position_m: float | None
    where: str = ""

    @property
    def end_s(self) -> float:
        return self.start_s + self.approach_s + self.hold_s + self.distance_m / self.velocity_m_per_s + \
            self.accel_s + self.lift_s


@dataclass
class SkinReplacement:
    """A fresh skin goes on at ``at_s`` (between slides): ridges new, history carried on."""

    at_s: float

    @property
    def start_s(self) -> float:
        return self.at_s


def build_slides(specs: list, skin: Skin, seed: int, wear: bool, contact_radius_at_1N_m: float):
    """Slides in time order on ``skin``: each trial starts on the skin as the earlier ones left it (Archard wear
    after each, if ``wear``; :class:`SkinReplacement` events put on a fresh skin); a start position not given is
    drawn from the scene seed and the trial's index. Returns (slides, skin states before each trial, the skin
    after the last)."""
    slides, states = [], []
    events = sorted(specs, key=lambda x: (x.start_s, isinstance(x, SlideSpec)))
    replacements = [e for e in events if isinstance(e, SkinReplacement)]
    for e in replacements:
        if any(sp.start_s < e.at_s < sp.end_s for sp in events if isinstance(sp, SlideSpec)):
            raise ValueError(f"the skin replacement at {e.at_s} s falls during a slide")
    k = -1
    for sp in events:
        if isinstance(sp, SkinReplacement):
            skin = skin.replace()
            continue
        k += 1
        position = sp.start_position_m
        if position is None:
            position = float(effect_rng(seed, f"slide[{k}].start_position").uniform(0.0, SURFACE_LENGTH_M))
        states.append(skin.state())
        slides.append(Slide(sp.start_s, sp.texture, sp.force_N, sp.velocity_m_per_s, sp.distance_m, sp.approach_s,
                            sp.hold_s, sp.accel_s, sp.lift_s, position, skin=copy.deepcopy(skin)))
        if wear:
            area = contact_patch_area_m2(sp.force_N, contact_radius_at_1N_m)
            skin.wear(sp.force_N, sp.distance_m, area, float(sp.texture.mu_kinetic), sp.velocity_m_per_s)
    return slides, states, skin


def _skin(c: _Checker, table) -> tuple[Skin, bool]:
    if not isinstance(table, dict):
        c.problems.append(f"skin = {_r(table)}: must be a table ([skin])")
        return Skin(), True
    c.known_keys(table, "skin", SKIN_FIELDS)
    fingerprints = c.boolean(table, "fingerprints", "skin", True)
    new_um = Skin().ridge_height_new_m * 1e6
    height = c.number(table, "ridge_height_um", "skin", 0.0, new_um, "µm", default=new_um)
    k = c.number(table, "wear_coefficient", "skin", 0.0, 1.0, "", default=Skin().wear_coefficient)
    wear = c.boolean(table, "wear", "skin", True)
    given = "ridge_height_um" in table and height is not None
    if given and fingerprints is False:
        c.problems.append(f"skin.ridge_height_um = {_r(table['ridge_height_um'])} with skin.fingerprints = false: a "
                          f"skin without fingerprints has no ridges (the height would be reported, not felt); give one "
                          f"or the other")
    return Skin(fingerprints=fingerprints, ridge_height_m=height / 1e6 if given else Skin().ridge_height_new_m,
                wear_coefficient=k if k is not None else Skin().wear_coefficient), wear


def _variant_electrodes(name: str) -> int:
    """How many electrodes a sensor variant has (19 for a name that is no variant: that problem is reported where
    the variant is read)."""
    from emulator.channels import VARIANTS, variant

    return variant(name).n_electrodes if name in VARIANTS else 19


FAULT_KEYS = ("electrode_open", "electrode_short", "mux_stuck", "thermistor", "heater_failed", "fluid_leak_mL_per_min",
              "fluid_leak_start_s")
MAX_LEAK_ML_PER_MIN = 60.0


def _faults(c: _Checker, table: dict, duration, n_electrodes: int = 19, where: str = "faults",
            hint: str = "") -> dict:
    """The sensor faults of the table ``where`` (``faults``: every sensor of the scene has them, so electrode numbers
    run 1..``n_electrodes``, the fewest any of its sensors has; ``sensor.faults``, ``sensors[i].faults``: one
    sensor's own, 1..its electrodes).  ``hint`` follows a refused electrode number (what limits it)."""
    c.known_keys(table, where, FAULT_KEYS)
    out = {}
    for key in ("electrode_open", "electrode_short"):
        if key in table:
            v = table[key]
            if isinstance(v, list) and len(v) > n_electrodes:  # (checked first: a huge list would take long)
                c.problems.append(f"{where}.{key}: {len(v)} entries; at most the {n_electrodes} electrodes")
            elif not isinstance(v, list) or not all(isinstance(n, int) and not isinstance(n, bool)
                                                    and 1 <= n <= n_electrodes for n in v):
                c.problems.append(f"{where}.{key} = {_r(v)}: a list of electrode numbers 1..{n_electrodes}{hint}")
            elif len(set(v)) < len(v):
                twice = sorted({n for n in v if v.count(n) > 1})
                c.problems.append(f"{where}.{key} = {_r(v)}: electrode {', '.join(map(str, twice))} listed more "
                                  f"than once")
            else:
                out[key] = v
    _open_and_short(c, (f"{where}.electrode_open", out.get("electrode_open", [])),
                    (f"{where}.electrode_short", out.get("electrode_short", [])), where)
    if "mux_stuck" in table:
        n = c.number(table, "mux_stuck", where, 1, n_electrodes, "electrode number", integer=True)
        if n is not None:
            out["mux_stuck"] = n
        else:
            c.problems[-1] += hint  # (c.number named the problem)
    if "thermistor" in table:
        v = c.choice(table, "thermistor", where, ("open", "short"))
        if v:
            out["thermistor"] = v
    if "heater_failed" in table:  # kept when false too: a finger's own "false" must not meet [faults]' "true" unseen
        if isinstance(table["heater_failed"], bool):
            out["heater_failed"] = table["heater_failed"]
        else:
            c.boolean(table, "heater_failed", where, False)  # the problem, named
    rate = c.number(table, "fluid_leak_mL_per_min", where, 0.0, MAX_LEAK_ML_PER_MIN, "mL/min")
    if "fluid_leak_start_s" in table and "fluid_leak_mL_per_min" not in table:
        c.problems.append(f"{where}.fluid_leak_start_s = {_r(table['fluid_leak_start_s'])}: a leak needs its rate "
                          f"too, in the same table ({where}.fluid_leak_mL_per_min, 0 to {MAX_LEAK_ML_PER_MIN:g} "
                          f"mL/min)")
    elif rate is not None:
        out["fluid_leak_mL_per_min"] = float(rate)
        if isinstance(table.get("fluid_leak_start_s"), list):
            c.problems.append(f"{where}.fluid_leak_start_s = {_r(table['fluid_leak_start_s'])}: one instant (s), "
                              f"not a list: a leak starts once")
        elif "fluid_leak_start_s" in table:
            start = c.times(table, "fluid_leak_start_s", where, duration)  # (a problem noted, if not an instant)
            if start:
                out["fluid_leak_start_s"] = start[0]
    return out


def _open_and_short(c: _Checker, opened: tuple, shorted: tuple, where: str) -> None:
    """An electrode both open and shorted is a problem; ``opened``, ``shorted``: (field name, its list)."""
    both = sorted(set(opened[1]) & set(shorted[1]))
    if both:
        c.problems.append(f"{where}: electrode {', '.join(map(str, both))} is both open ({opened[0]} = "
                          f"{_r(opened[1])}) and shorted ({shorted[0]} = {_r(shorted[1])}); an electrode is one or "
                          f"the other")


def _sensor_faults(c: _Checker, table: dict, where: str, duration, variant: str) -> dict:
    """A sensor's own faults: the ``faults`` sub-table of its [sensor] or [[sensors]] table ({} if none), electrode
    numbers 1..its variant's electrodes."""
    if "faults" not in table:
        return {}
    own = table["faults"]
    if not isinstance(own, dict):
        c.problems.append(f"{where}.faults = {_r(own)}: must be a table ([{where.split('[')[0]}.faults] after the "
                          f"sensor's table) of faults by name: {', '.join(FAULT_KEYS)}")
        return {}
    n = _variant_electrodes(variant)
    return _faults(c, own, duration, n, f"{where}.faults", f" (this sensor is a {_r(variant)})")


def _with_common_faults(c: _Checker, common: dict, own: dict, where: str) -> dict:
    """A sensor's faults: the scene's [faults] every sensor has and its own ``where`` (a fault given in both places
    is refused: which one holds would be a guess)."""
    for key in sorted(set(common) & set(own)):
        c.problems.append(f"{where}.{key}: [faults] already gives {key} = {_r(common[key])} to every sensor of the "
                          f"scene; give a fault in one place (in [faults] for all, or in each sensor's own table)")
    for opens, shorts in ((("faults", common), (where, own)), ((where, own), ("faults", common))):
        if "electrode_open" in opens[1] and "electrode_short" in shorts[1]:
            _open_and_short(c, (f"{opens[0]}.electrode_open", opens[1]["electrode_open"]),
                            (f"{shorts[0]}.electrode_short", shorts[1]["electrode_short"]), where)
    return {**common, **own}


def _frame(variant: str) -> tuple[str, ...]:
    """The default frame of a sensor variant (what ``host.sequence = "default"`` reads from it)."""
    from emulator.channels import variant as variant_of

    return variant_of(variant).frame_names


def _check_host(c: _Checker, sequence, slot_rate: float, clock: float, duration: float,
                variant: str = "biotac") -> None:
    """What the sampler would refuse, and sequences the scene is too short to read even once, as problems
    (``variant``: whose default frame "default" reads — the longest of the scene's sensors')."""
    from emulator.spi.peripheral import TRANSFER_PERIODS

    word_s = TRANSFER_PERIODS / clock  # the same rule as bench.running.sampler.Sampler
    if 2 * word_s + proto.SAMPLE_DELAY_S > 1.0 / slot_rate:
        c.problems.append(f"host.slot_rate_Hz = {slot_rate:g}: a slot of {1e6 / slot_rate:.1f} µs cannot hold the "
                          f"command, {proto.SAMPLE_DELAY_S * 1e6:.0f} µs and the read at host.spi_clock_Hz = "
                          f"{clock:g}; lower slot_rate_Hz or raise the clock")
    seq = list(_frame(variant) if sequence == "default" else sequence)
    slots = int(round(duration * slot_rate))  # what the runner reads
    first = {}
    for i, n in enumerate(seq):
        first.setdefault(n, i)
    unread = [n for n, i in first.items() if i >= slots]
    if unread:
        c.problems.append(f"scene.duration_s = {duration:g}: at host.slot_rate_Hz = {slot_rate:g} the scene reads "
                          f"{slots} slot(s), so {', '.join(unread[:5])}{', ...' if len(unread) > 5 else ''} of the "
                          f"host sequence ({len(seq)} slots) would never be read; make the scene at least "
                          f"{max(first.values()) + 1} slots ({(max(first.values()) + 1) / slot_rate:.3g} s) long")


def _slot_gaps(seq: list, channel: str) -> list[int]:
    """Gaps (in slots) between consecutive reads of ``channel`` in the repeating sequence."""
    at = [i for i, n in enumerate(seq) if n == channel]
    return [b - a for a, b in zip(at, at[1:] + [at[0] + len(seq)])] if at else []


def _check_slides(c: _Checker, specs: list, sequence, slot_rate: float, variant: str = "biotac") -> None:
    """Every sliding trial's texture properties (traction, roughness, fineness: bench.textures.properties) must be
    computable from what the host reads from the sliding sensor (of ``variant``); otherwise the scene is refused
    here, not after it ran."""
    import statistics

    from bench.textures.properties import (BACKGROUND_GUARD_S, BAND_HZ, MEASURE_LEAD, MEASURE_TAIL)
    from emulator.sliding import SlidingContact

    specs = [x for x in specs if isinstance(x, SlideSpec)]  # a skin replacement alone reads nothing
    if not specs:
        return
    seq = list(_frame(variant) if sequence == "default" else sequence)
    missing = [n for n in ("PAC", "PDC") if n not in seq]
    if missing:
        c.problems.append(f"host.sequence = {_r(sequence)}: a sliding scene reports each trial's texture properties "
                          f"from PAC and PDC; add {' and '.join(missing)} to the host sequence")
        return
    pac_Hz = slot_rate / statistics.median(_slot_gaps(seq, "PAC"))
    if not BAND_HZ[1] < pac_Hz / 2:
        c.problems.append(f"host.slot_rate_Hz = {slot_rate:g}: PAC is read at {pac_Hz:.4g} Hz, and the roughness of "
                          f"a sliding trial needs its {BAND_HZ[1]:g} Hz band below Nyquist: more than "
                          f"{2 * BAND_HZ[1]:g} Hz of PAC")
    pdc_gap_s = max(_slot_gaps(seq, "PDC")) / slot_rate
    measured = 1.0 - MEASURE_LEAD - MEASURE_TAIL
    need_s = 2.0 / SlidingContact.LOG_RATE_HZ  # the stage current comes from the contact's 100 Hz force log
    seen = set()
    for sp in specs:
        if sp.where in seen:  # the trials of one [[stimulus]] have one shape: its problems are reported once
            continue
        seen.add(sp.where)
        slide_s = sp.distance_m / sp.velocity_m_per_s + sp.accel_s
        if slide_s * measured < need_s:
            c.problems.append(f"{sp.where}: the slide lasts {slide_s * 1e3:.3g} ms; its texture properties are "
                              f"measured over the middle {measured:.0%} of it and need at least {need_s * 1e3:g} ms "
                              f"there (at least {need_s / measured * 1e3:.3g} ms of sliding): slide farther or slower")
        if sp.hold_s <= 2 * BACKGROUND_GUARD_S:
            c.problems.append(f"{sp.where}.hold_s = {sp.hold_s:g}: a sliding trial's roughness subtracts the "
                              f"vibration of the hold before the slide, less {BACKGROUND_GUARD_S:g} s at both ends; "
                              f"hold longer than {2 * BACKGROUND_GUARD_S:g} s")
        if pdc_gap_s > sp.end_s - sp.start_s:
            c.problems.append(f"{sp.where}: PDC is read every {pdc_gap_s:.3g} s, so a trial of "
                              f"{sp.end_s - sp.start_s:.3g} s may hold no PDC sample; read PDC more often")


def _check_impact_detection(c: _Checker, sequence, slot_rate: float, duration: float, stimuli,
                            variant: str = "biotac", sensor: int | None = None) -> None:
    """``impact_detection`` needs PAC at a rate the rule can use on each sensor with sphere drops (``stimuli``:
    sensor ``sensor``'s, of ``variant``), and time after each drop for the rule's window."""
    min_points, window_s = IMPACT_RULE_MIN_POINTS, IMPACT_RULE_WINDOW_S
    on = f" (sensor {sensor})" if sensor is not None else ""
    seq = list(_frame(variant) if sequence == "default" else sequence)
    if "PAC" not in seq:
        problem = (f"analysis.impact_detection = true: the rule reads PAC, and host.sequence = {_r(sequence)} "
                   f"does not read it; add \"PAC\" or switch impact detection off")
        if problem not in c.problems:
            c.problems.append(problem)
        return
    pac_Hz = slot_rate * seq.count("PAC") / len(seq)
    need_Hz = (min_points + 1) / window_s
    if pac_Hz < need_Hz:
        c.problems.append(f"analysis.impact_detection = true{on}: PAC is read at {pac_Hz:.3g} Hz (host.slot_rate_Hz = "
                          f"{slot_rate:g}, {seq.count('PAC')} of {len(seq)} slots); the rule needs more than "
                          f"{min_points} samples within {window_s * 1e3:.0f} ms, so at least {need_Hz:g} Hz")
    for s in (x for x in stimuli if isinstance(x, SphereDrop)):
        if s.time_s + window_s > duration:
            c.problems.append(f"analysis.impact_detection = true: the sphere drop at {s.time_s} s{on} is judged over "
                              f"{window_s * 1e3:.0f} ms after it, past the end of the scene (duration_s = "
                              f"{duration:g}); drop it earlier or lengthen the scene")


def _unit_value(c: _Checker, table: dict, where: str):
    """``table["unit"]``: a unit seed (whole number), "nominal", or a serial number ("BT..."); None if invalid."""
    from emulator.units import MAX_UNIT_SEED, NOMINAL, SERIAL_PREFIX, serial_problem

    v = table.get("unit", NOMINAL)
    if isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= MAX_UNIT_SEED:
        return v
    if isinstance(v, str) and v == NOMINAL:
        return v
    if isinstance(v, str) and v.startswith(SERIAL_PREFIX):
        if problem := serial_problem(v):  # a valid serial, and a seed in range if it names one
            c.problems.append(f"{where}.unit = {_r(v)}: {problem}")
            return None
        return v
    c.problems.append(f"{where}.unit = {_r(v)}: a unit seed 0 to {MAX_UNIT_SEED} (e.g. unit = 17), \"{NOMINAL}\", "
                      f"or a serial number starting with \"{SERIAL_PREFIX}\" (biotac-bench units)")
    return None


class _SensorTable(NamedTuple):
    """What a [sensor] or [[sensors]] table says: unit name, variant, parameters (the unit's with the table's
    overrides on top), serial, the sensor's own faults, and the table's name in messages."""

    unit: str
    variant: str
    params: SensorParams
    serial: str
    faults: dict
    where: str


def _sensor_table(c: _Checker, table: dict, where: str, duration, extra=()) -> _SensorTable:
    """The :class:`_SensorTable` of ``table`` (named ``where``), its problems noted."""
    from emulator.channels import VARIANTS
    from emulator.spi.model import serial_variant_problem
    from emulator.units import unit as make_unit

    c.known_keys(table, where, set(PARAMETER_FIELDS) | set(SENSOR_KEYS) | {"faults"} | set(extra))
    which = _unit_value(c, table, where)
    variant = c.choice(table, "variant", where, VARIANTS, default="biotac") or "biotac"
    changes = {}
    for k, v in table.items():
        if k in PARAMETER_FIELDS:
            if isinstance(v, int) and not isinstance(v, bool) and not _real(v):  # (a bool: not a number)
                unit_, (lo, hi) = PARAMETER_FIELDS[k].metadata["unit"], PARAMETER_FIELDS[k].metadata["range"]
                c.problems.append(f"{where}.{k} = {_r(v)}: allowed range is {lo} to {hi} {unit_}")
                continue
            try:
                check_parameter(k, v, where=f"{where}.{k}", spell=_r)
                changes[k] = v
            except (ValueError, TypeError, OverflowError) as e:
                c.problems.append(_cut(str(e)))
    u = make_unit(which if which is not None else None)
    if which is not None and table.get("variant", "biotac") in VARIANTS:  # (a bad variant is its own problem)
        if problem := serial_variant_problem(u.serial, variant):
            c.problems.append(f"{where}.unit = {_r(which)}: {problem}")
    params = dataclasses.replace(u.params, **changes)  # (each value checked above)
    if inconsistent := params.inconsistencies(where):  # values each in range that no sensor can have together
        c.problems += inconsistent
        params = u.params
    return _SensorTable(u.name, variant, params, u.serial, _sensor_faults(c, table, where, duration, variant), where)


def _one_finger_per_unit(c: _Checker, tables: dict) -> None:
    """A unit is one real device with one serial: two fingers given the same unit (the nominal unit aside, whose
    fingers each keep their port's default serial) are a problem naming both."""
    from emulator.units import NOMINAL

    first: dict[str, int] = {}
    for n, t in sorted(tables.items()):
        if t.unit == NOMINAL:
            continue
        if t.serial in first:
            m = first[t.serial]
            c.problems.append(f"{t.where}.unit: sensor {n} is given unit {t.unit} (serial {t.serial}), already sensor "
                              f"{m}'s ({'[sensor]' if m == 1 else tables[m].where}): a unit is one real device, so each finger needs its own "
                              f"(another seed or serial)")
        else:
            first[t.serial] = n


def _sensors_tables(c: _Checker, items, duration) -> dict:
    """Sensors 2..N from ``[[sensors]]``: number -> :class:`_SensorTable`."""
    out: dict = {}
    if isinstance(items, dict):
        c.problems.append(f"sensors = {_r(items)}: must be an array of tables ([[sensors]]), one per sensor 2.."
                          f"{MAX_SENSORS}, each with its index (sensor 1 is [sensor])")
        return out
    if not isinstance(items, list) or not all(isinstance(t, dict) for t in items):
        c.problems.append(f"sensors = {_r(items)}: must be an array of tables ([[sensors]] with index = 2.."
                          f"{MAX_SENSORS}, unit, variant, parameters)")
        return out
    seen: dict[int, str] = {}
    for i, t in enumerate(items):
        w = f"sensors[{i}]"
        if "index" in t and t["index"] == 1 and not isinstance(t["index"], bool):
            c.problems.append(f"{w}.index = 1: sensor 1 is described by the [sensor] table; [[sensors]] describes "
                              f"sensors 2..{MAX_SENSORS}")
            continue
        k = c.number(t, "index", w, 2, MAX_SENSORS, "(a sensor number)", required=True, integer=True)
        spec = _sensor_table(c, t, w, duration, extra=("index",))
        if k is None:
            continue
        if k in seen:
            c.problems.append(f"{w}.index = {k}: sensor {k} is already described by {seen[k]}")
            continue
        seen[k] = w
        out[k] = spec
    return out


def _library(c: _Checker, meta: dict, source: str):
    """The scene's texture library: ``[scene] library`` (a path relative to the scene file, as an experiment file
    names one: :func:`bench.textures.library.named_library`) read and validated; :data:`_SHIPPED` if the scene
    names none; None, its problems noted, if the file named cannot be read or is invalid."""
    from bench.errors import TextureError
    from bench.textures.library import named_library

    if "library" not in meta:
        return _SHIPPED
    try:
        return named_library(meta["library"], "scene.library", source)
    except TextureError as e:
        c.problems += [_cut(p, 600) for p in e.problems]
        return None


def parse_scene(data: dict, source: str = "<scene>", text: str = "") -> Scene:
    """Validate a scene given as a dict (the parsed TOML); raise :class:`SceneError` listing every problem."""
    c = _Checker()
    if not isinstance(data, dict):
        raise SceneError(source, [f"the scene is {_r(data)}: it must be a table of tables ([scene], [host], "
                                  f"[[stimulus]], ...)"])
    c.known_keys(data, "scene file", {"scene", "sensor", "sensors", "host", "noise", "stimulus", "analysis", "faults",
                                      "skin"})
    meta = c.table(data, "scene", "it needs at least name and duration_s")
    if "scene" not in data:
        c.problems.append("[scene] table is missing (needs at least name and duration_s)")
    c.known_keys(meta, "scene", {"name", "description", "duration_s", "seed", "fidelity", "library"})
    name = meta.get("name")
    if "scene" in data and not isinstance(data["scene"], dict):
        pass  # the table's shape is the problem; its fields are not looked for
    elif problem := folder_name_problem(name, "scene.name"):
        c.problems.append(problem)
    duration = c.number(meta, "duration_s", "scene", 1e-3, MAX_DURATION_S, "s",
                        required=isinstance(data.get("scene", {}), dict))
    seed = c.number(meta, "seed", "scene", 0, MAX_SEED, "", default=0, integer=True)
    fidelity = c.choice(meta, "fidelity", "scene", tuple(PROFILES), default="default")
    description = meta.get("description", "")
    if not isinstance(description, str):
        c.problems.append(f"scene.description = {_r(description)}: must be a string")
        description = ""
    elif tomlfile.unprintable(description, allowed="\n\t"):
        c.problems.append(f"scene.description = {_r(description)}: must be printable text (line breaks and tabs "
                          f"aside, no control characters: it is printed and written into report.md)")
        description = ""

    sensor = c.table(data, "sensor", "sensor 1: unit, variant and parameters by name (biotac-bench params, "
                                     "biotac-bench units), its own faults in [sensor.faults]")
    first = _sensor_table(c, sensor, "sensor", duration)
    unit, variant, params, serial = first.unit, first.variant, first.params, first.serial
    others = _sensors_tables(c, data.get("sensors", []), duration)
    _one_finger_per_unit(c, {1: first, **others})

    host = c.table(data, "host", "sequence, slot_rate_Hz, spi_clock_Hz, spi")
    c.known_keys(host, "host", {"sequence", "slot_rate_Hz", "spi_clock_Hz", "spi"})
    spi = c.choice(host, "spi", "host", SPI_SIDES, default="software")
    sequence = host.get("sequence", "default")
    host_problems = len(c.problems)
    if sequence != "default":
        if not isinstance(sequence, list) or not sequence:
            c.problems.append(f"host.sequence = {_r(sequence)}: \"default\" or a non-empty list of channel names")
            sequence = "default"
        else:
            # E20..E24 when a sensor is a BioTac SP (a 19-electrode sensor answers them with error words)
            sp = "biotac-sp" in {variant, *(o.variant for o in others.values())}
            known = ALL_CHANNEL_INDEX if sp else CHANNEL_INDEX
            for i, n in enumerate(sequence):
                if not isinstance(n, str) or n.upper() not in known or n.upper() == "HAL":
                    c.problems.append(f"host.sequence[{i}] = {_r(n)}: channels are PAC, PDC, TAC, TDC, "
                                      + ("E1..E24" if sp else "E1..E19 (E20..E24 with a \"biotac-sp\" sensor)"))
            sequence = [n.upper() for n in sequence if isinstance(n, str) and n.upper() in known]
    slot_rate = c.number(host, "slot_rate_Hz", "host", 1.0, 8000.0, "Hz", default=4400.0)
    lo, hi = proto.SPI_CLOCK_RANGE_HZ
    clock = c.number(host, "spi_clock_Hz", "host", lo, hi, "Hz", default=proto.HOST_DEFAULT_CLOCK_HZ)
    host_ok = len(c.problems) == host_problems and isinstance(data.get("host", {}), dict)

    noise_t = c.table(data, "noise", "noise sources by name, each true or false")
    names = NoiseSources.__dataclass_fields__.keys()
    c.known_keys(noise_t, "noise", names)
    noise = NoiseSources(**{k: c.boolean(noise_t, k, "noise", True) for k in names})

    textures = _library(c, meta, source)
    targets: list[int] = []
    stimuli = _stimuli(c, data.get("stimulus", []), duration, params, targets,
                       params_of=lambda k: others[k].params if k in others else params,
                       variant_of=lambda k: others[k].variant if k in others else variant, textures=textures)
    if len(stimuli) > MAX_INSTANTS:
        c.problems.append(f"stimulus: {len(stimuli)} stimuli (every instant of every [[stimulus]] counts): at most "
                          f"{MAX_INSTANTS} per scene")
    skin, wear = _skin(c, data.get("skin", {}))
    # every sensor's stimuli (1: the scene's own); sensors addressed but not declared share sensor 1's unit
    per_sensor: dict[int, list] = {1: []}
    for s, k in zip(stimuli, targets):
        per_sensor.setdefault(k, []).append(s)
    slide_specs_of = {k: [s for s in lst if isinstance(s, (SlideSpec, SkinReplacement))]
                      for k, lst in per_sensor.items()}
    per_sensor = {k: [s for s in lst if not isinstance(s, (SlideSpec, SkinReplacement))]
                  for k, lst in per_sensor.items()}
    slide_specs = slide_specs_of[1]
    stimuli = per_sensor[1]
    for k, specs in slide_specs_of.items():
        ordered = sorted((s for s in specs if isinstance(s, SlideSpec)), key=lambda x: x.start_s)
        for a, b in zip(ordered, ordered[1:]):
            if b.start_s < a.end_s:
                c.problems.append(f"{b.where}: the slide starting at {b.start_s} s overlaps the one of {a.where} "
                                  f"(from {a.start_s} s to {a.end_s:.3f} s); one finger slides on one texture at a "
                                  f"time" + (f" (both on sensor {k})" if k != 1 else ""))
        for press in (x for x in per_sensor.get(k, []) if isinstance(x, (Tap, Press))):
            for a in ordered:
                if press.start_s < a.end_s and a.start_s < press.end_s:
                    c.problems.append(f"the {type(press).__name__.lower()} from {press.start_s:g} s to "
                                      f"{press.end_s:.3f} s{f' on sensor {k}' if k != 1 else ''} falls during the "
                                      f"slide of {a.where} ({a.start_s} s to {a.end_s:.3f} s): the slide sets the "
                                      f"finger's normal force; give it another finger or another time")
        for r in (s for s in specs if isinstance(s, SkinReplacement)):
            for a in ordered:
                if a.start_s < r.at_s < a.end_s:
                    c.problems.append(f"replace_skin at {r.at_s} s falls during the slide of {a.where} "
                                      f"({a.start_s} s to {a.end_s:.3f} s)")
    # the faults every sensor has ([faults]: electrodes 1..the fewest any sensor has), then each sensor's own
    n_electrodes = min(_variant_electrodes(v) for v in {variant, *(o.variant for o in others.values())})
    common = _faults(c, c.table(data, "faults", ", ".join(FAULT_KEYS)), duration, n_electrodes,
                     hint="" if n_electrodes > 19 else " (every sensor of the scene has the [faults]; a \"biotac-sp\"'s "
                                                       "E20..E24 go in its own [sensor.faults] or [sensors.faults])")
    tables = {1: first, **others}
    faults_of = {k: _with_common_faults(c, common, t.faults, f"{t.where}.faults") for k, t in tables.items()}
    analysis = c.table(data, "analysis", "impact_detection = true | false")
    c.known_keys(analysis, "analysis", {"impact_detection"})
    impact_detection = c.boolean(analysis, "impact_detection", "analysis", False)
    for k, lst in per_sensor.items():
        if not faults_of.get(k, common).get("heater_failed"):
            continue
        said_by = f"{tables[k].where}.faults" if k in tables and tables[k].faults.get("heater_failed") else "faults"
        for s in (x for x in lst if isinstance(x, HeaterFailure)):
            c.problems.append(f"heater_failure at {s.at_s} s{f' (sensor {k})' if k != 1 else ''}: {said_by}."
                              f"heater_failed = true says the heaters never ran, so they cannot fail during the run; "
                              f"give one or the other")
    for k, lst in per_sensor.items():
        thermal = sorted((x for x in lst if isinstance(x, Touch) and x.material is not None), key=lambda x: x.start_s)
        for i, a in enumerate(thermal):
            for b in thermal[i + 1:]:
                same_place = (a.electrode == b.electrode if a.electrode or b.electrode
                              else (a.x_mm, a.angle_deg) == (b.x_mm, b.angle_deg))
                if (same_place and b.start_s < a.end_s
                        and (a.material, a.object_temperature_C) != (b.material, b.object_temperature_C)):
                    place = f"over {a.electrode}" if a.electrode else f"at x = {a.x_mm:g} mm, {a.angle_deg:g}°"
                    what = [f"{x.material} at " + ("room temperature" if x.object_temperature_C is None else
                                                   f"{x.object_temperature_C} °C") for x in (a, b)]
                    c.problems.append(f"two objects touch {place} at once{f' on sensor {k}' if k != 1 else ''}: "
                                      f"{what[0]} from {a.start_s:g} s and {what[1]} from {b.start_s:g} s "
                                      f"(until {a.end_s:.3f} s); one place meets one object at a time")
        steps: dict[float, float] = {}
        for s in lst:
            if isinstance(s, AmbientStep):
                if steps.get(s.at_s, s.temperature_C) != s.temperature_C:
                    c.problems.append(f"ambient_step at {s.at_s} s: two room temperatures at one instant "
                                      f"({steps[s.at_s]} and {s.temperature_C} °C)"
                                      + (f" for sensor {k}" if k != 1 else ""))
                steps[s.at_s] = s.temperature_C
    if host_ok and duration is not None:
        variant_of = {k: others[k].variant if k in others else variant for k in (1, *others, *slide_specs_of)}
        longest = max(set(variant_of.values()), key=lambda v: len(_frame(v)))
        _check_host(c, sequence, float(slot_rate), float(clock), float(duration), longest)
        for k, specs in slide_specs_of.items():
            _check_slides(c, specs, sequence, float(slot_rate), variant_of[k])
        if impact_detection:
            judged = {k: lst for k, lst in per_sensor.items() if any(isinstance(x, SphereDrop) for x in lst)}
            if not judged:
                c.problems.append("analysis.impact_detection = true: the scene has no sphere_drop to judge"
                                  + (" on any sensor" if len(per_sensor) > 1 else ""))
            for k, lst in sorted(judged.items()):
                _check_impact_detection(c, sequence, float(slot_rate), float(duration), lst,
                                        variant_of.get(k, variant), sensor=k if len(per_sensor) > 1 else None)

    if fidelity and duration:
        from emulator.fidelity import profile

        grid = profile(fidelity).grid_Hz
        for k, s in ((k, x) for k, lst in per_sensor.items() for x in lst):
            if not isinstance(s, (Vibration, PressureCalibrator)) and not contact_place(s):
                continue
            # which one: its start (and finger), as the other checks across stimuli name it (two identical lines
            # had said nothing of which vibration or pressure stimulus was meant)
            which = f"the stimulus starting at {s.start_s:g} s{f' on sensor {k}' if k != 1 else ''}: "
            if isinstance(s, Vibration) and max(s.f_start_Hz, s.f_stop_Hz or 0) >= 0.45 * grid:
                top = max(s.f_start_Hz, s.f_stop_Hz or 0)
                # the profiles whose grid computes it (the advice had been "reference" alone, where "default" does)
                fits = " or ".join(f'"{n}"' for n, f in PROFILES.items() if top < 0.45 * f.grid_Hz)
                c.problems.append(f"{which}vibration at {top:.0f} Hz needs a finer grid than "
                                  f"fidelity '{fidelity}' ({grid:.0f} Hz); use {fits}")
            elif isinstance(s, PressureCalibrator) and s.amplitude_Pa > 0 and s.frequency_Hz >= 0.45 * grid:
                c.problems.append(f"{which}pressure at {s.frequency_Hz:.0f} Hz needs a finer grid than fidelity "
                                  f"'{fidelity}' ({grid:.0f} Hz); use \"default\" or \"reference\"")
            elif placed_contact_too_short(s, profile(fidelity).electrode_rate_Hz):
                rate, (span_s, fields) = profile(fidelity).electrode_rate_Hz, contact_span(s)
                fits = " or ".join(f'"{n}"' for n, f in PROFILES.items()
                                     if not placed_contact_too_short(s, f.electrode_rate_Hz))
                c.problems.append(f"{which}a {type(s).__name__.lower()} of {span_s * 1e3:g} ms ({fields}) at a "
                                  f"place is shorter than two steps of the electrodes' model at fidelity "
                                  f"'{fidelity}' ({rate:.0f} Hz: at least {PLACED_CONTACT_MIN_STEPS * 1e3 / rate:g} "
                                  f"ms); lengthen {fields}" + (f" or use {fits}" if fits else ""))
    if c.problems:
        raise SceneError(source, c.problems)
    fresh_skin = copy.deepcopy(skin)
    skin_before = skin.state()
    slides, trial_skins, skin = build_slides(slide_specs, skin, int(seed), wear, params.contact_radius_at_1N_m)
    stimuli += slides
    sensors = {}
    for k in sorted(set(others) | set(per_sensor)):
        if k == 1:
            continue
        t = others.get(k, first)  # not declared: sensor 1's twin (no serial of its own), with the common faults
        u, var, p_k, ser = t.unit, t.variant, t.params, (t.serial if k in others else "")
        own = copy.deepcopy(fresh_skin)  # each finger its own skin, as the [skin] table describes it
        before = own.state()
        slides_k, skins_k, own = build_slides(slide_specs_of.get(k, []), own, sensor_seed(int(seed), k), wear,
                                              p_k.contact_radius_at_1N_m)
        sensors[k] = SensorSpec(k, u, ser, p_k, var, per_sensor.get(k, []) + slides_k, before, own.state(), skins_k,
                                dict(faults_of.get(k, common)))
    if textures is _SHIPPED and any(isinstance(s, SlideSpec) for lst in slide_specs_of.values() for s in lst):
        from bench.textures.library import read_library

        textures = read_library()  # the one the slides' textures came from, for the record
    return Scene(name=name, duration_s=float(duration), seed=int(seed), fidelity=fidelity,
                 description=description, params=params, sequence=sequence,
                 slot_rate_Hz=float(slot_rate), spi_clock_Hz=float(clock), spi=spi, noise=noise, stimuli=stimuli,
                 faults=faults_of[1], common_faults=dict(common),
                 impact_detection=impact_detection, source=source, text=text,
                 skin_before=skin_before, skin_after=skin.state(), trial_skins=trial_skins,
                 unit=unit, serial=serial, variant=variant, sensors=sensors,
                 library=None if textures is _SHIPPED else textures.record())


def read_scene_text(path: str | Path) -> str:
    """The text of a scene file, or :class:`SceneError` naming the file and what is wrong with it (see
    :func:`bench.tomlfile.read_text`: unreadable, not a regular file, larger than :data:`MAX_SCENE_BYTES`, empty,
    not UTF-8, a NUL byte)."""
    return tomlfile.read_text(path, SceneError, MAX_SCENE_BYTES,
                              "a scene needs at least a [scene] table with name and duration_s",
                              "give a scene file, e.g. fixtures/scenes/taps.toml")


def parse_scene_text(text: str, source: str = "<scene>", overrides: dict | None = None) -> Scene:
    """Parse and validate a scene file's text; :class:`SceneError` names ``source`` for any problem.

    ``overrides``: values that replace the file's before validation, by ``"table.field"`` (e.g. ``{"scene.seed":
    5, "scene.fidelity": "fast", "host.spi": "rtl"}``: ``run``'s command-line options), so that the scene that
    runs is the scene that was validated; the scene keeps them in ``Scene.overrides``."""
    data = tomlfile.parse(text, source, SceneError, MAX_NESTING, "a scene needs 4 levels")
    overrides = dict(overrides or {})
    for key, value in overrides.items():
        table, _, name = key.partition(".")
        if table not in TABLES or not name:
            raise ValueError(f"override {key!r}: give table.field, e.g. scene.seed")
        if table == "scene" and table not in data:
            continue  # the missing [scene] table is reported as such
        if isinstance(data.setdefault(table, {}), dict):  # a table of the wrong shape is reported as such
            data[table][name] = value
    scene = parse_scene(data, source=source, text=text)
    scene.overrides = overrides
    return scene


def load_scene(path: str | Path, overrides: dict | None = None) -> Scene:
    """Read and validate a scene file (see :func:`read_scene_text` for what makes a file unreadable;
    ``overrides`` as for :func:`parse_scene_text`)."""
    return parse_scene_text(read_scene_text(path), source=str(path), overrides=overrides)


def with_overrides(scene: Scene, overrides: dict) -> Scene:
    """``scene`` with ``overrides`` (as :func:`parse_scene_text` takes them, e.g. ``{"scene.seed": 5}``) over its own
    values and over those it was read with: read again from its text and validated again, as ``biotac-bench run``
    applies its options — so a seed also redraws what the scene draws from it (its slides' placements), and a
    fidelity profile whose grid cannot compute a stimulus is refused (:class:`SceneError`).  A scene made or
    changed in code (no text, or not what its text reads as) gets the fields replaced as they are, its changes kept."""
    import dataclasses

    if not overrides:
        return scene
    if scene.text and parse_scene_text(scene.text, source=scene.source, overrides=scene.overrides) == scene:
        return parse_scene_text(scene.text, source=scene.source, overrides={**scene.overrides, **overrides})
    return dataclasses.replace(scene, **{key.partition(".")[2]: value for key, value in overrides.items()})

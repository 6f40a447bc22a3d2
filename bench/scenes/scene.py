"""Scene files: what happens to the finger, what the host reads, which noise, which fidelity, which seed.

A scene is a TOML file validated completely before anything runs; every problem is reported
with the file, the field (``stimulus[2].frequency_Hz``), the value and what is allowed.
See ``fixtures/scenes/`` for examples and ``biotac-bench run --help`` for the format.
"""

from __future__ import annotations

import copy
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from bench.errors import SceneError
from emulator.channels import CHANNEL_INDEX
from emulator.fidelity import PROFILES
from emulator.params import PARAMETER_FIELDS, SensorParams, check_parameter
from emulator.sensor import NoiseSources
from emulator.spi import protocol as proto
from emulator.stimuli import (DROP_HEIGHT_M, SPHERES, AmbientStep, HeaterFailure, PowerOn, Press, PressureCalibrator,
                              SphereDrop, Tap, Touch, Vibration)
from emulator.effects import effect_rng
from emulator.skin import Skin
from emulator.sliding import Slide
from emulator.texture import SURFACE_LENGTH_M
from emulator.thermal import MATERIALS

MAX_DURATION_S = 36000.0


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

    @property
    def channels(self) -> list[str]:
        from emulator.channels import DEFAULT_FRAME_NAMES

        seq = DEFAULT_FRAME_NAMES if self.sequence == "default" else self.sequence
        return sorted(set(seq), key=lambda n: CHANNEL_INDEX[n])


class _Checker:
    """Collects problems while reading a table of values."""

    def __init__(self):
        self.problems: list[str] = []

    def number(self, table: dict, key: str, where: str, lo: float, hi: float, unit: str,
               default=None, required=False, integer=False):
        if key not in table:
            if required:
                self.problems.append(f"{where}.{key} is missing ({unit}, {lo} to {hi})")
            return default
        v = table[key]
        kind = "a whole number" if integer else "a number"
        if isinstance(v, bool) or not isinstance(v, (int, float)) or (integer and not isinstance(v, int)):
            self.problems.append(f"{where}.{key} = {v!r}: must be {kind} in {unit} ({lo} to {hi})")
            return default
        if not math.isfinite(v) or not lo <= v <= hi:
            self.problems.append(f"{where}.{key} = {v!r}: allowed range is {lo} to {hi} {unit}")
            return default
        return v

    def times(self, table: dict, key: str, where: str, duration: float | None, required=True):
        if key not in table:
            if required:
                self.problems.append(f"{where}.{key} is missing (an instant in s, or a list of instants)")
            return []
        v = table[key]
        values = v if isinstance(v, list) else [v]
        out = []
        for i, t in enumerate(values):
            name = f"{where}.{key}[{i}]" if isinstance(v, list) else f"{where}.{key}"
            if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t) or t < 0:
                self.problems.append(f"{name} = {t!r}: must be an instant ≥ 0 s")
            elif duration is not None and t >= duration:
                self.problems.append(f"{name} = {t!r} s: after the end of the scene (duration_s = {duration})")
            else:
                out.append(float(t))
        return out

    def choice(self, table, key, where, choices, default=None, required=False):
        if key not in table:
            if required:
                self.problems.append(f"{where}.{key} is missing; one of: {', '.join(map(str, choices))}")
            return default
        v = table[key]
        if v not in choices:
            self.problems.append(f"{where}.{key} = {v!r}: must be one of: {', '.join(map(str, choices))}")
            return default
        return v

    def boolean(self, table, key, where, default):
        v = table.get(key, default)
        if not isinstance(v, bool):
            self.problems.append(f"{where}.{key} = {v!r}: must be true or false")
            return default
        return v

    def known_keys(self, table: dict, where: str, known):
        for k in table:
            if k not in known:
                self.problems.append(f"{where}: unknown field {k!r}; known fields: {', '.join(sorted(known))}")


STIMULUS_KINDS = ("tap", "press", "touch", "sphere_drop", "vibration", "pressure", "power_on", "ambient_step",
                  "heater_failure", "slide", "replace_skin")
_STIMULUS_FIELDS = {
    "tap": {"kind", "at_s", "peak_N", "duration_s"},
    "press": {"kind", "start_s", "force_N", "ramp_s", "hold_s"},
    "sphere_drop": {"kind", "at_s", "sphere", "mass_mg", "height_m"},
    "vibration": {"kind", "start_s", "duration_s", "amplitude_um", "frequency_Hz", "f_start_Hz", "f_stop_Hz", "fade_s"},
    "pressure": {"kind", "start_s", "duration_s", "offset_kPa", "amplitude_Pa", "frequency_Hz", "fade_s"},
    "touch": {"kind", "start_s", "force_N", "ramp_s", "hold_s", "x_mm", "angle_deg", "electrode",
              "indenter_radius_mm", "tangential_N", "shear_angle_deg", "material", "object_temperature_C"},
    "power_on": {"kind", "at_s"},
    "ambient_step": {"kind", "at_s", "temperature_C"},
    "heater_failure": {"kind", "at_s"},
    "replace_skin": {"kind", "at_s"},
    "slide": {"kind", "start_s", "texture", "force_N", "velocity_mm_per_s", "distance_mm", "approach_s", "hold_s",
              "accel_s", "lift_s", "start_position_mm"},
}
SKIN_FIELDS = {"fingerprints", "ridge_height_um", "wear", "wear_coefficient"}
ELECTRODE_NAMES = tuple(f"E{n}" for n in range(1, 20))


def _stimuli(c: _Checker, items, duration, params: SensorParams):
    out = []
    if not isinstance(items, list):
        c.problems.append("stimulus must be an array of tables ([[stimulus]])")
        return out
    for i, st in enumerate(items):
        w = f"stimulus[{i}]"
        if not isinstance(st, dict):
            c.problems.append(f"{w} must be a table")
            continue
        kind = c.choice(st, "kind", w, STIMULUS_KINDS, required=True)
        if kind is None:
            continue
        c.known_keys(st, w, _STIMULUS_FIELDS[kind])
        if kind == "tap":
            peak = c.number(st, "peak_N", w, 0.0, 50.0, "N", required=True)
            dur = c.number(st, "duration_s", w, 1e-3, 10.0, "s", default=0.03)
            for t in c.times(st, "at_s", w, duration):
                if peak is not None and dur is not None:
                    out.append(Tap(t, peak, dur))
        elif kind == "press":
            start = c.times(st, "start_s", w, duration)
            force = c.number(st, "force_N", w, 0.0, 50.0, "N", required=True)
            ramp = c.number(st, "ramp_s", w, 1e-3, 3600.0, "s", default=0.5)
            hold = c.number(st, "hold_s", w, 0.0, 36000.0, "s", default=1.0)
            if start and None not in (force, ramp, hold):
                out.append(Press(start[0], force, ramp, hold))
        elif kind == "sphere_drop":
            height = c.number(st, "height_m", w, 1e-3, 10.0, "m", default=DROP_HEIGHT_M)
            if "sphere" in st and "mass_mg" in st:
                c.problems.append(f"{w}: give either sphere or mass_mg, not both")
            if "mass_mg" in st:
                mass_mg = c.number(st, "mass_mg", w, 1e-4, 1e4, "mg")
                mass = None if mass_mg is None else mass_mg * 1e-6
            else:
                name = c.choice(st, "sphere", w, tuple(SPHERES), required=True)
                mass = None if name is None else SPHERES[name][0]
            for t in c.times(st, "at_s", w, duration):
                if mass is not None and height is not None:
                    out.append(SphereDrop(t, mass, height, params.impact_restitution, params.impact_contact_s))
        elif kind == "vibration":
            start = c.times(st, "start_s", w, duration)
            dur = c.number(st, "duration_s", w, 1e-3, MAX_DURATION_S, "s", required=True)
            amp = c.number(st, "amplitude_um", w, 0.0, 1000.0, "µm", required=True)
            fade = c.number(st, "fade_s", w, 0.0, 10.0, "s", default=0.01)
            if "frequency_Hz" in st:
                f0 = c.number(st, "frequency_Hz", w, 1.0, 3000.0, "Hz")
                f1 = None
                if "f_start_Hz" in st or "f_stop_Hz" in st:
                    c.problems.append(f"{w}: give frequency_Hz for a tone or f_start_Hz and f_stop_Hz for a sweep")
            else:
                f0 = c.number(st, "f_start_Hz", w, 1.0, 3000.0, "Hz", required=True)
                f1 = c.number(st, "f_stop_Hz", w, 1.0, 3000.0, "Hz", required=True)
            if start and None not in (dur, amp, fade, f0):
                out.append(Vibration(start[0], dur, amp * 1e-6, f0, f1, fade))
        elif kind == "pressure":
            start = c.times(st, "start_s", w, duration)
            dur = c.number(st, "duration_s", w, 1e-3, MAX_DURATION_S, "s", required=True)
            offset = c.number(st, "offset_kPa", w, -100.0, 200.0, "kPa", default=0.0)
            amp = c.number(st, "amplitude_Pa", w, 0.0, 1e5, "Pa", default=0.0)
            freq = c.number(st, "frequency_Hz", w, 0.0, 3000.0, "Hz", default=0.0)
            fade = c.number(st, "fade_s", w, 0.0, 10.0, "s", default=0.01)
            if start and None not in (dur, offset, amp, freq, fade):
                out.append(PressureCalibrator(start[0], dur, offset * 1e3, amp, freq, fade))
        elif kind == "touch":
            start = c.times(st, "start_s", w, duration)
            vals = dict(
                force_N=c.number(st, "force_N", w, 0.0, 50.0, "N", required=True),
                ramp_s=c.number(st, "ramp_s", w, 1e-3, 3600.0, "s", default=0.5),
                hold_s=c.number(st, "hold_s", w, 0.0, 36000.0, "s", default=1.0),
                x_mm=c.number(st, "x_mm", w, -20.0, 8.0, "mm", default=-5.0),
                angle_deg=c.number(st, "angle_deg", w, -180.0, 180.0, "°", default=0.0),
                indenter_radius_mm=c.number(st, "indenter_radius_mm", w, 0.1, 15.0, "mm", default=3.0),
                tangential_N=c.number(st, "tangential_N", w, -20.0, 20.0, "N", default=0.0),
                shear_angle_deg=c.number(st, "shear_angle_deg", w, -180.0, 180.0, "°", default=0.0),
                object_temperature_C=c.number(st, "object_temperature_C", w, -40.0, 120.0, "°C"),
            )
            electrode = c.choice(st, "electrode", w, ELECTRODE_NAMES)
            mat = c.choice(st, "material", w, tuple(MATERIALS))
            if start and None not in [v for k, v in vals.items() if k != "object_temperature_C"]:
                out.append(Touch(start[0], electrode=electrode, material=mat, **vals))
        elif kind == "power_on":
            at = c.times(st, "at_s", w, duration)
            out += [PowerOn(a) for a in at[:1]]
        elif kind == "heater_failure":
            out += [HeaterFailure(a) for a in c.times(st, "at_s", w, duration)[:1]]
        elif kind == "ambient_step":
            at = c.times(st, "at_s", w, duration)
            temp = c.number(st, "temperature_C", w, -20.0, 60.0, "°C", required=True)
            if at and temp is not None:
                out.append(AmbientStep(at[0], temp))
        elif kind == "slide":
            out += _slides(c, st, w, duration)
        elif kind == "replace_skin":
            out += [SkinReplacement(t) for t in c.times(st, "at_s", w, duration)]
    return out


def _slides(c: _Checker, st: dict, w: str, duration) -> list[SlideSpec]:
    """One :class:`SlideSpec` per start instant (a list of ``start_s`` is a list of trials)."""
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
    else:
        try:
            tex = find_texture(st["texture"])
        except TextureError as e:
            c.problems.append(f"{w}.texture = {st['texture']!r}: " + "; ".join(e.problems))
    if tex is None or None in [v for k, v in vals.items() if k != "start_position_mm"]:
        return []
    v, d, a = vals["velocity_mm_per_s"] * 1e-3, vals["distance_mm"] * 1e-3, vals["accel_s"]
    if d < v * a:
        c.problems.append(f"{w}.distance_mm = {vals['distance_mm']!r}: shorter than the stage's acceleration and "
                          f"braking at this velocity ({v * a * 1e3:.3g} mm); lower accel_s or slide farther")
        return []
    out = []
    for t in starts:
        spec = SlideSpec(t, tex, vals["force_N"], v, d, vals["approach_s"], vals["hold_s"], a, vals["lift_s"],
                         None if vals["start_position_mm"] is None else vals["start_position_mm"] * 1e-3, where=w)
        if duration is not None and spec.end_s > duration:
            c.problems.append(f"{w}: the slide starting at {t} s ends at {spec.end_s:.3f} s, after the end of the "
                              f"scene (duration_s = {duration})")
            continue
        out.append(spec)
    return out


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
            area = math.pi * (contact_radius_at_1N_m * sp.force_N ** (1 / 3)) ** 2
            skin.wear(sp.force_N, sp.distance_m, area, float(sp.texture.mu_kinetic), sp.velocity_m_per_s)
    return slides, states, skin


def _skin(c: _Checker, table) -> tuple[Skin, bool]:
    if not isinstance(table, dict):
        c.problems.append(f"skin = {table!r}: must be a table ([skin])")
        return Skin(), True
    c.known_keys(table, "skin", SKIN_FIELDS)
    fingerprints = c.boolean(table, "fingerprints", "skin", True)
    new_um = Skin().ridge_height_new_m * 1e6
    height = c.number(table, "ridge_height_um", "skin", 0.0, new_um, "µm", default=new_um)
    k = c.number(table, "wear_coefficient", "skin", 0.0, 1.0, "", default=Skin().wear_coefficient)
    wear = c.boolean(table, "wear", "skin", True)
    given = "ridge_height_um" in table and height is not None
    return Skin(fingerprints=fingerprints, ridge_height_m=height * 1e-6 if given else Skin().ridge_height_new_m,
                wear_coefficient=k if k is not None else Skin().wear_coefficient), wear


def _faults(c: _Checker, table: dict) -> dict:
    c.known_keys(table, "faults", {"electrode_open", "electrode_short", "mux_stuck", "thermistor", "heater_failed"})
    out = {}
    for key in ("electrode_open", "electrode_short"):
        if key in table:
            v = table[key]
            if not isinstance(v, list) or not all(isinstance(n, int) and 1 <= n <= 19 for n in v):
                c.problems.append(f"faults.{key} = {v!r}: a list of electrode numbers 1..19")
            else:
                out[key] = v
    if "mux_stuck" in table:
        n = c.number(table, "mux_stuck", "faults", 1, 19, "electrode number", integer=True)
        if n is not None:
            out["mux_stuck"] = n
    if "thermistor" in table:
        v = c.choice(table, "thermistor", "faults", ("open", "short"))
        if v:
            out["thermistor"] = v
    if c.boolean(table, "heater_failed", "faults", False):
        out["heater_failed"] = True
    return out


def parse_scene(data: dict, source: str = "<scene>", text: str = "") -> Scene:
    """Validate a scene given as a dict (the parsed TOML); raise :class:`SceneError` listing every problem."""
    c = _Checker()
    c.known_keys(data, "scene file", {"scene", "sensor", "host", "noise", "stimulus", "analysis", "faults", "skin"})
    meta = data.get("scene", {})
    if "scene" not in data:
        c.problems.append("[scene] table is missing (needs at least name and duration_s)")
    c.known_keys(meta, "scene", {"name", "description", "duration_s", "seed", "fidelity"})
    name = meta.get("name")
    if not isinstance(name, str) or not name:
        c.problems.append(f"scene.name = {name!r}: must be a non-empty string")
    elif len(name) > 100 or name in (".", "..") or not all(ch.isascii() and (ch.isalnum() or ch in "-_.")
                                                           for ch in name):
        c.problems.append(f"scene.name = {name!r}: must be a name, not a path (it names the default out "
                          f"folder): 1 to 100 letters, digits, '-', '_' or '.', and not '.' or '..'")
    duration = c.number(meta, "duration_s", "scene", 1e-3, MAX_DURATION_S, "s", required=True)
    seed = c.number(meta, "seed", "scene", 0, 2**63 - 1, "", default=0, integer=True)
    fidelity = c.choice(meta, "fidelity", "scene", tuple(PROFILES), default="default")

    sensor = data.get("sensor", {})
    c.known_keys(sensor, "sensor", PARAMETER_FIELDS)
    changes = {}
    for k, v in sensor.items():
        if k in PARAMETER_FIELDS:
            try:
                check_parameter(k, v, where=f"sensor.{k}")
                changes[k] = v
            except ValueError as e:
                c.problems.append(str(e))
    params = SensorParams().replace(**changes)

    host = data.get("host", {})
    c.known_keys(host, "host", {"sequence", "slot_rate_Hz", "spi_clock_Hz", "spi"})
    spi = c.choice(host, "spi", "host", ("software", "rtl"), default="software")
    sequence = host.get("sequence", "default")
    if sequence != "default":
        if not isinstance(sequence, list) or not sequence:
            c.problems.append(f"host.sequence = {sequence!r}: \"default\" or a non-empty list of channel names")
            sequence = "default"
        else:
            for i, n in enumerate(sequence):
                if not isinstance(n, str) or n.upper() not in CHANNEL_INDEX or n.upper() == "HAL":
                    c.problems.append(f"host.sequence[{i}] = {n!r}: channels are PAC, PDC, TAC, TDC, E1..E19")
            sequence = [n.upper() for n in sequence if isinstance(n, str)]
    slot_rate = c.number(host, "slot_rate_Hz", "host", 1.0, 8000.0, "Hz", default=4400.0)
    lo, hi = proto.SPI_CLOCK_RANGE_HZ
    clock = c.number(host, "spi_clock_Hz", "host", lo, hi, "Hz", default=proto.HOST_DEFAULT_CLOCK_HZ)

    noise_t = data.get("noise", {})
    names = NoiseSources.__dataclass_fields__.keys()
    c.known_keys(noise_t, "noise", names)
    noise = NoiseSources(**{k: c.boolean(noise_t, k, "noise", True) for k in names})

    stimuli = _stimuli(c, data.get("stimulus", []), duration, params)
    skin, wear = _skin(c, data.get("skin", {}))
    slide_specs = [s for s in stimuli if isinstance(s, (SlideSpec, SkinReplacement))]
    stimuli = [s for s in stimuli if not isinstance(s, (SlideSpec, SkinReplacement))]
    ordered = sorted((s for s in slide_specs if isinstance(s, SlideSpec)), key=lambda x: x.start_s)
    for a, b in zip(ordered, ordered[1:]):
        if b.start_s < a.end_s:
            c.problems.append(f"{b.where}: the slide starting at {b.start_s} s overlaps the one of {a.where} "
                              f"(from {a.start_s} s to {a.end_s:.3f} s); one finger slides on one texture at a time")
    for r in (s for s in slide_specs if isinstance(s, SkinReplacement)):
        for a in ordered:
            if a.start_s < r.at_s < a.end_s:
                c.problems.append(f"replace_skin at {r.at_s} s falls during the slide of {a.where} "
                                  f"({a.start_s} s to {a.end_s:.3f} s)")
    faults = _faults(c, data.get("faults", {}))
    analysis = data.get("analysis", {})
    c.known_keys(analysis, "analysis", {"impact_detection"})
    impact_detection = c.boolean(analysis, "impact_detection", "analysis", False)

    if fidelity and duration:
        from emulator.fidelity import profile

        grid = profile(fidelity).grid_Hz
        for i, s in enumerate(stimuli):
            if isinstance(s, Vibration) and max(s.f_start_Hz, s.f_stop_Hz or 0) >= 0.45 * grid:
                c.problems.append(f"vibration at {max(s.f_start_Hz, s.f_stop_Hz or 0):.0f} Hz needs a finer grid than "
                                  f"fidelity '{fidelity}' ({grid:.0f} Hz); use \"reference\"")
    if c.problems:
        raise SceneError(source, c.problems)
    skin_before = skin.state()
    slides, trial_skins, skin = build_slides(slide_specs, skin, int(seed), wear, params.contact_radius_at_1N_m)
    stimuli += slides
    return Scene(name=name, duration_s=float(duration), seed=int(seed), fidelity=fidelity,
                 description=str(meta.get("description", "")), params=params, sequence=sequence,
                 slot_rate_Hz=float(slot_rate), spi_clock_Hz=float(clock), spi=spi, noise=noise, stimuli=stimuli,
                 faults=faults,
                 impact_detection=impact_detection, source=source, text=text,
                 skin_before=skin_before, skin_after=skin.state(), trial_skins=trial_skins)


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise SceneError(str(path), [f"cannot read the file: {e.strerror}"]) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(str(path), [f"TOML syntax error: {e}"]) from None
    return parse_scene(data, source=str(path), text=text)

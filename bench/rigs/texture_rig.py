"""The texture rig of D ch. 6, as a real control loop through the emulated sensor.

A stepper lowers the finger at 0.5 mm/s until the PDC change read over SPI reaches the target (force control
through PDC: the rig converts the target force to PDC counts with the published 11.5 mN per bit, so sensor noise
and skin and texture compliance decide the force it actually reaches); it holds ~0.5 s; a linear stage slides
the texture at the set velocity over the set distance while the stage's motor current — rising linearly with
the tangential load — is sampled at the frame rate; then the finger lifts.  The controller sees only codes: it
reads the sensor through the host sampler and the SPI peripheral like any host.  Each texture is one 75 mm
square, as D's were; a trial starts at a random place on it, drawn from the trial's seed, such that the contact
patch stays on the square from touchdown to the end of the stroke (:meth:`TextureRig.start_range_m`).

Timing, as D ch. 6 describes its rig (l. 1216–1220): "Data was sampled continuously and transmitted back to the
computer in batches every 100ms. The digital controls for the stepper motor were also updated every 100ms through a
DAQ card".  Modelled so: the host samples frame after frame (10 ms each) without pause; the frames reach the
controller in batches of ``batch_s`` (0.1 s), each batch at its end; the controller evaluates its rules on every
frame of a batch when the batch arrives, and a command it then gives (the lowering once the baseline has arrived,
the stop once a frame of the batch reaches the target) is given at that arrival and reaches the motor
``latency_s`` later.  The stop frame is therefore still the first frame whose PDC change reaches the target, but
the finger keeps lowering until the end of that frame's batch plus the latency — on average half a batch more than
a controller deciding after every frame.  Model choices, not D's: the batches are aligned to the start of sampling
(batch k holds frames 10k … 10k + 9), the DAQ update is taken to happen at the batch's arrival (D updated the
stepper "every 100ms" too, in step or not with the data, which D does not say), and ``latency_s`` = 20 ms between
arrival and the motor's response (the host's processing and the DAQ's output; D gives no figure).  A ``batch_s``
of one frame is a controller deciding after every frame.  The commands planned in advance from the stop (the hold,
the slide's start and braking, the lift) are given at their planned instants, not on the batch ticks: the linear
stage ran its own motion controller from preset commands (D), and the lift comes after everything the properties
use.  The stage's motor current is recorded once per frame, not at D's 100 ms queries: the traction (the mean
current over the measurement window, D eq. 6.14) estimates the same mean from ten times the readings (a choice: the
means agree within 1 %; 100 ms queries would widen the trial-to-trial spread by up to ~7× on smooth textures, where
the current-sense noise, a model figure not D's, dominates it).

While lowering, to avoid paying a Python round trip per frame, the emulator reads stretches of frames as if the
finger kept lowering (which it does until the controller's stop acts) and checks the controller's rule on every
frame read.  Each stretch is computed in one block that ends exactly at its last frame's needs.  A stretch that may
hold the stop is read after a snapshot (a deep copy of the run, :func:`_clone`); if the stop's batch ends before
the stretch does, the emulator goes back to the snapshot, gives the stop command at the batch's end (it acts a
latency later, after everything computed) and reads on through that batch — the same samples, since results do not
depend on block size (tested); if the batch ends after the stretch, it reads on to the batch's end from there.  The
motion refuses a command that would reach into computed instants.  The lowering command, which follows the
baseline whatever it reads, is given before the baseline is read, so the baseline and the first stretch are one
read.  Stretches the stop is not expected in are read without a snapshot: the stop is predicted
from the PDC change read so far against the commanded load ahead (the contact law of the planned depth), with a
margin; should the stop still fall inside one, the lowering is run again from the trial's start with a snapshot
before every window (deterministic from the seed, so the same trial; counted in ``Trial.extra["lowering"]``).
None of this changes what the controller sees or decides (tested).  From the stop the motion is fixed in advance:
the frames a reader of ``chunk_s`` at a time would read until the trial's end are computed in as few exact blocks as
memory allows.

:func:`movement_grid` gives the 36 movements of D eqs 6.20–6.21.
"""

from __future__ import annotations

import copy
import copyreg
import dataclasses
import math
import numbers
import re
from dataclasses import dataclass, field

import numpy as np

from bench.running.sampler import STATUS_NAMES, STATUS_OK, Sampler
from bench.tomlfile import spelled
from bench.textures.properties import TrialRecording
from bench.textures.stage import StageMotor
from emulator import channels as ch
from emulator.effects import effect_rng
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.skin import Skin, contact_patch_area_m2, contact_patch_radius_m
from emulator.sliding import CommandedMotion, contact_force_from_depth
from emulator.stimuli import MountVibration
from emulator.spi.model import Faults
from emulator.spi.peripheral import SoftwarePeripheral
from emulator.texture import Texture

FORCE_PER_PDC_BIT_N = 0.0115  # the rig's calibration: the published 11.5 mN per PDC bit (D ch. 4)
#: the smallest target PDC change (counts) the rig takes: 4 × the PDC's ~0.5 count RMS reading noise (noise budget).
#: Below it the stop rule fires on noise, with the finger still in the air (a 0.01 N target, 0.87 counts, stopped in
#: the air in 1 of 4 trials on foam); D's forces are 0.2–2 N (17–174 counts)
MIN_TARGET_COUNTS = 2.0


@dataclass(frozen=True)
class Movement:
    """An exploratory movement: normal force (N) and sliding velocity (m/s)."""

    force_N: float
    velocity_m_per_s: float

    @property
    def power_W(self) -> float:
        """Sliding power scale N·v (equal along the grid's anti-diagonals)."""
        return self.force_N * self.velocity_m_per_s

    def label(self) -> str:
        return f"{self.force_N:.2f} N @ {self.velocity_m_per_s * 100:.2f} cm/s"


def movement_grid() -> list[Movement]:
    """The 36 movements of D eqs 6.20–6.21: v_i = 10^((i−1)/5) cm/s, F_j = 0.2·10^((j−1)/5) N, i, j = 1..6."""
    return [Movement(0.2 * 10 ** ((j - 1) / 5), 0.01 * 10 ** ((i - 1) / 5)) for j in range(1, 7) for i in range(1, 7)]


#: settings that must be > 0, and why (a zero had passed the ≥ 0 check and ended in a bare ZeroDivisionError)
_RIG_POSITIVE = {"lower_rate_m_per_s": "the finger lowers at this rate until the target",
                 "stage_accel_m_per_s2": "the stage ramps to the velocity and back at it",
                 "lift_rate_m_per_s": "the finger lifts off at this rate",
                 "chunk_s": "the run is read in chunks of this length",
                 "speculation_s": "the longest window read while lowering"}


@dataclass
class RigSettings:
    """The rig's mechanics and timing (SI units)."""

    lower_rate_m_per_s: float = 0.5e-3  # D ch. 6
    start_gap_m: float = 0.2e-3  # finger above the texture when the trial starts
    baseline_s: float = 0.2  # PDC and PAC at rest before lowering
    hold_s: float = 0.5  # D ch. 6: "held for ~0.5 s"
    distance_m: float = 0.05
    #: D ch. 6: the textures were cut into 75 mm squares; every trial of a texture runs on its one square (the first
    #: 75 mm of the texture's periodic surface), starting at a random place on it
    texture_side_m: float = 0.075
    stage_accel_m_per_s2: float = 1.0
    lift_rate_m_per_s: float = 5e-3
    settle_after_s: float = 0.2
    #: D ch. 6: data reached the computer "in batches every 100ms" and the stepper's controls were "updated every
    #: 100ms"; a whole number of frames (one frame: a controller deciding after every frame)
    batch_s: float = 0.1
    latency_s: float = 0.02  # from a batch's arrival to the motor's response (a model choice)
    # D ch. 6: the stepper stops "when this value [the DC pressure] reached the target change" — each frame's
    # reading itself; averaging n frames (a choice D does not describe) adds (n − 1)/2 frames of lag
    pdc_average_frames: int = 1
    motor: StageMotor = field(default_factory=StageMotor)  # the stage's motor current (traction)
    chunk_s: float = 0.5
    speculation_s: float = 1.0  # while lowering: the longest window read after a snapshot (s)
    #: D ch. 6: "even when locked in a fixed position, the stepper motor produced some background noise that was not
    #: consistent from trial to trial" (D subtracts it: the roughness's background).  Its median RMS in the PAC band
    #: (Pa; 0: a silent stepper, the default, as D gives no level) and its trial-to-trial spread (the standard
    #: deviation of its natural log): each trial draws its level from its seed, on for the whole trial
    stepper_noise_Pa: float = 0.0
    stepper_noise_log_spread: float = 0.5

    def __post_init__(self):
        for name, value in vars(self).items():
            if isinstance(value, (int, float)) and not isinstance(value, bool) and not (math.isfinite(value)
                                                                                          and value >= 0):
                raise ValueError(f"rig.{name} = {value!r}: must be a finite number ≥ 0")
        for name, what in _RIG_POSITIVE.items():  # each divides the trial's timing: 0 would never end or divide by 0
            value = getattr(self, name)
            if not (isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_)) and value > 0):
                raise ValueError(f"rig.{name} = {value!r}: must be a number > 0 ({what})")
        frames = self.pdc_average_frames
        if not (isinstance(frames, numbers.Integral) and not isinstance(frames, (bool, np.bool_)) and frames >= 1):
            raise ValueError(f"rig.pdc_average_frames = {self.pdc_average_frames!r}: a whole number of frames ≥ 1 "
                             f"(1: each frame's own reading)")
        self.pdc_average_frames = int(frames)  # (numpy's integers too)
        if self.stepper_noise_log_spread > 3.0:
            raise ValueError(f"rig.stepper_noise_log_spread = {self.stepper_noise_log_spread!r}: at most 3 (a factor "
                             f"of e^3 ≈ 20 either way for one standard deviation)")


@dataclass(frozen=True)
class SpiFaultWindow:
    """SPI faults (:class:`emulator.spi.model.Faults`) on the rig's bus from ``start_s`` to ``end_s`` (s from the
    trial's start, the sampler's clock): every slot whose sampling command starts in [start_s, end_s) is exchanged
    with them in force (fault injection over SPI, as a flaky cable or a disturbed bus would)."""

    start_s: float
    end_s: float
    faults: Faults

    def __post_init__(self):
        if not (isinstance(self.faults, Faults) and all(isinstance(v, numbers.Real) and math.isfinite(v)
                                                         for v in (self.start_s, self.end_s))
                and 0 <= self.start_s < self.end_s):
            raise ValueError(f"SpiFaultWindow({self.start_s!r}, {self.end_s!r}, {self.faults!r:.80}): start_s and "
                             f"end_s in s, 0 ≤ start_s < end_s, and an emulator.spi.model.Faults")


#: a declared SPI fault window's span (s from the trial's start) and the settings it may put on the bus (the fields of
#: :class:`emulator.spi.model.Faults`): an experiment file's ``[rig] spi_faults`` entries and ``texture-sweep
#: --spi-fault`` take these fields, and :func:`spi_fault_text` writes them so
SPI_FAULT_SPAN = ("start_s", "end_s")
SPI_FAULT_SETTINGS = tuple(f.name for f in dataclasses.fields(Faults))
#: the most fault windows one declaration takes (each a stretch of the trial: a few are all a trial has room for)
MAX_SPI_FAULT_WINDOWS = 100


def _fault_allowed(setting: str, value) -> str | None:
    """What :class:`Faults` allows for ``setting`` (a field of it) in a file's words, or None when it takes
    ``value``: Faults's own check, its "None or" left out (a declaration leaves a setting out instead)."""
    try:
        Faults(**{setting: value})
    except ValueError as e:
        allowed = re.sub(r"^None(,| or) ", "", str(e).split(": must be ", 1)[-1])
        return allowed.replace("True or False", "true or false")
    return None


def spi_fault_windows(declared, where: str) -> tuple[tuple[SpiFaultWindow, ...], list[str]]:
    """The SPI fault windows ``declared`` (a list of tables, each ``start_s`` and ``end_s`` in s from the trial's
    start and at least one setting of :data:`SPI_FAULT_SETTINGS`) and the problems found, each naming
    ``where[i].field``, the value and what is allowed (no window when there is any problem).  Windows may not
    overlap: which faults would be in force there?"""
    fields = SPI_FAULT_SPAN + SPI_FAULT_SETTINGS
    if not isinstance(declared, list) or len(declared) > MAX_SPI_FAULT_WINDOWS:
        return (), [f"{where} = {spelled(declared)}: a list of at most {MAX_SPI_FAULT_WINDOWS} windows, each a table "
                    f"of start_s and end_s (s from the trial's start, 0 ≤ start_s < end_s) and the faults in force "
                    f"then ({', '.join(SPI_FAULT_SETTINGS)})"]
    problems: list[str] = []
    windows = []
    for i, table in enumerate(declared):
        at = f"{where}[{i}]"
        if not isinstance(table, dict):
            problems.append(f"{at} = {spelled(table)}: a table of {', '.join(fields)}")
            continue
        unknown = [f"{at}: unknown field {spelled(k)}; known: {', '.join(fields)}" for k in table if k not in fields]
        problems += unknown
        span = {}
        for key in SPI_FAULT_SPAN:
            v = table.get(key)
            if key not in table:
                problems.append(f"{at}.{key} is missing: a number of seconds ≥ 0 from the trial's start")
            elif isinstance(v, bool) or not isinstance(v, numbers.Real) or not (math.isfinite(v) and v >= 0):
                problems.append(f"{at}.{key} = {spelled(v)}: must be a number of seconds ≥ 0 from the trial's start")
            else:
                span[key] = float(v)
        if len(span) == 2 and not span["start_s"] < span["end_s"]:
            problems.append(f"{at}.end_s = {spelled(table['end_s'])}: must be after start_s = "
                            f"{spelled(table['start_s'])}")
        settings = {k: table[k] for k in SPI_FAULT_SETTINGS if k in table}
        bad = {k: why for k, v in settings.items() if (why := _fault_allowed(k, v)) is not None}
        problems += [f"{at}.{k} = {spelled(settings[k])}: must be {why}" for k, why in bad.items()]
        if unknown or bad or len(span) < 2 or not span["start_s"] < span["end_s"]:
            continue
        faults = Faults(**settings)
        if not faults.any:
            problems.append(f"{at} = {spelled(table)}: sets no fault; give at least one of "
                            f"{', '.join(SPI_FAULT_SETTINGS)}")
            continue
        windows.append((i, SpiFaultWindow(span["start_s"], span["end_s"], faults)))
    ordered = sorted(windows, key=lambda iw: iw[1].start_s)
    for (i, a), (j, b) in zip(ordered, ordered[1:]):
        if b.start_s < a.end_s:
            problems.append(f"{where}[{j}] ({b.start_s:g} to {b.end_s:g} s) overlaps {where}[{i}] ({a.start_s:g} to "
                            f"{a.end_s:g} s): windows may not overlap (whose faults would be in force?)")
    return (() if problems else tuple(w for _, w in windows)), problems


def _text_value(text: str):
    """A value of :func:`spi_fault_text`'s form as the file would hold it: true/false, a whole number, a number, or
    the text itself (refused by :func:`spi_fault_windows`, which names it)."""
    if text in ("true", "false"):
        return text == "true"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


#: how a window is written as text (:func:`spi_faults_from_text`), as an error shows it
SPI_FAULT_FORM = "start_s=S,end_s=S,SETTING=VALUE,... (e.g. start_s=0.3,end_s=0.4,miso_flip_bit=1)"


def spi_faults_from_text(text: str, where: str) -> tuple[tuple[SpiFaultWindow, ...], list[str]]:
    """The windows ``text`` declares (:func:`spi_fault_text`'s form: ``start_s=S,end_s=S,SETTING=VALUE,...``, windows
    joined by ``;``; "" none) and the problems found (:func:`spi_fault_windows`'s, the i-th window ``where[i]``)."""
    declared, problems = [], []
    for i, part in enumerate(p.strip() for p in text.split(";") if p.strip()):
        items = [item.strip() for item in part.split(",") if item.strip()]
        unpaired = [item for item in items if "=" not in item]
        if unpaired:
            problems.append(f"{where}[{i}] = {spelled(part)}: {spelled(unpaired[0])} is no FIELD=VALUE; write "
                            f"{SPI_FAULT_FORM}")
            continue
        declared.append({k.strip(): _text_value(v.strip()) for k, v in (item.split("=", 1) for item in items)})
    if problems:
        return (), problems
    return spi_fault_windows(declared, where)


def spi_fault_text(windows) -> str:
    """``windows`` (:class:`SpiFaultWindow` each) as text, the form :func:`spi_faults_from_text` reads back to the
    same windows: ``start_s=0.25,end_s=0.35,miso_flip_bit=1`` (the settings a window sets, in
    :data:`SPI_FAULT_SETTINGS`' order), windows joined by ``; ``; "" for none."""
    def value(v) -> str:
        return ("true" if v else "false") if isinstance(v, bool) else repr(v)

    def set_(v) -> bool:  # (a bit 0 or stuck-at-0 is a fault set: only None and False are none)
        return v is not None and v is not False

    return "; ".join(",".join([f"start_s={w.start_s!r}", f"end_s={w.end_s!r}"]
                              + [f"{k}={value(getattr(w.faults, k))}" for k in SPI_FAULT_SETTINGS
                                 if set_(getattr(w.faults, k))])
                     for w in windows)


@dataclass
class Trial:
    """One trial's recording (for the properties), its true forces, and what the controller did.  ``extra``:
    ``"lowering"`` (what the emulator did while lowering) and ``"rejected_samples"`` (the samples the host
    flagged bad, left out of the recording and of the controller's decisions: ``{channel: {status: count}}``)."""

    recording: TrialRecording
    movement: Movement
    true_normal_N: float  # mean true normal load during the slide (the emulator's contact force, not a code)
    reached_pdc_change: float  # PDC change (counts) of the stop frame (the first to reach the target)
    skin_before: dict
    skin_after: dict
    texture: int
    trial: int
    start_position_m: float
    wall_s: float = 0.0
    frames: int = 0
    extra: dict = field(default_factory=dict)


class TextureRig:
    """The rig with one skin: trials run one after another on the same skin (which wears)."""

    def __init__(self, skin: Skin | None = None, params: SensorParams | None = None, fidelity: str = "default",
                 noise: NoiseSources = NoiseSources(), settings: RigSettings | None = None, wear: bool = True,
                 spi_faults: tuple[SpiFaultWindow, ...] = ()):
        self.skin = skin or Skin()
        self.params = params or SensorParams()
        self.fidelity, self.noise = fidelity, noise
        self.settings = settings or RigSettings()
        self.wear = wear
        self.spi_faults = tuple(spi_faults)  # each trial's bus, from its start (:class:`SpiFaultWindow`)
        if not all(isinstance(w, SpiFaultWindow) for w in self.spi_faults):
            raise ValueError(f"spi_faults = {spi_faults!r:.120}: SpiFaultWindow(start_s, end_s, Faults(...)) each")

    def run_trial(self, texture: Texture, movement: Movement, seed: int, trial: int = 0) -> Trial:
        """Lower, hold, slide, lift: one trial on ``texture``; ``seed`` decides the start position and every
        noise stream, so a trial is the same whatever else ran before it (given the skin's state)."""
        return self._trial(texture, movement, seed, trial, self._lowered_ahead)

    def _trial(self, texture: Texture, movement: Movement, seed: int, trial: int, lower) -> Trial:
        """:meth:`run_trial`, lowered by ``lower(texture, movement, seed, start_position)``, which returns what
        :meth:`_lowered` does."""
        import time

        wall0 = time.perf_counter()
        s = self.settings
        if not (movement.force_N > 0 and movement.velocity_m_per_s > 0):
            raise ValueError(f"movement {movement}: force and velocity must be positive")
        if movement.force_N / FORCE_PER_PDC_BIT_N < MIN_TARGET_COUNTS:
            raise ValueError(f"movement {movement}: a {movement.force_N:g} N target is a PDC change of "
                             f"{movement.force_N / FORCE_PER_PDC_BIT_N:.2f} counts, within the PDC's reading noise "
                             f"(~0.5 count RMS), so the stepper could stop in the air; the rig needs at least "
                             f"{MIN_TARGET_COUNTS:g} counts ({MIN_TARGET_COUNTS * FORCE_PER_PDC_BIT_N:g} N)")
        first, last = self.start_range_m(movement)
        start_position = float(effect_rng(seed, "rig.start_position").uniform(first, last))
        run, reached, lowering, to_stop = lower(texture, movement, seed, start_position)
        frame_s = run.frame / run.sampler.slot_rate_Hz
        motion, sampler, log = run.motion, run.sampler, run.log
        t_stop = (sampler.next_slot + to_stop * run.frame) / sampler.slot_rate_Hz  # the stop frame's batch arrives
        contact_s = motion.move_finger(t_stop, 0.0)
        # hold, then slide over the distance: the stage starts, cruises and brakes at planned instants
        slide_start = contact_s + s.hold_s
        v, acc = movement.velocity_m_per_s, s.stage_accel_m_per_s2
        ramp = v / acc
        cruise = max(0.0, s.distance_m / v - ramp)
        motion.move_stage(slide_start - s.latency_s, v, acc)
        brake = slide_start + ramp + cruise
        motion.move_stage(brake - s.latency_s, 0.0, acc)
        slide_end = brake + ramp
        motion.move_finger(slide_end - s.latency_s, -s.lift_rate_m_per_s)
        end = slide_end + s.settle_after_s + (s.start_gap_m + 3e-3) / s.lift_rate_m_per_s
        # the motion is fixed from here: the frames a reader of chunk_s at a time reads until the end, read in as few
        # blocks as memory allows (each computed exactly: no grid beyond the last frame)
        chunk = max(1, int(round(s.chunk_s / frame_s)))
        rest = 0
        while (sampler.next_slot + (to_stop + rest) * run.frame) / sampler.slot_rate_Hz < end:
            rest += chunk
        rest += to_stop  # (the frames through the stop, if the lowering went back to before them)
        for part in np.array_split(np.arange(rest), math.ceil(rest * frame_s * run.sensor.fs / _MAX_BLOCK_SAMPLES)):
            run.read_exactly(part.size)
        true_normal = log.mean_load(slide_start + ramp, brake)
        skin_before = self.skin.state()
        if self.wear:
            area = contact_patch_area_m2(movement.force_N, self.params.contact_radius_at_1N_m)
            self.skin.wear(movement.force_N, s.distance_m, area, float(texture.mu_kinetic), movement.velocity_m_per_s)
        rec = log.recording(contact_s, slide_start, slide_end, texture.number, movement, trial, seed)
        return Trial(rec, movement, true_normal, reached, skin_before, self.skin.state(), texture.number, trial,
                     start_position, time.perf_counter() - wall0, log.n_frames(run.frame),
                     {"lowering": lowering, "rejected_samples": log.rejected()})

    def stepper_noise_Pa(self, seed: int) -> float:
        """The stepper's background (RMS Pa in the PAC band) during the trial of ``seed``: the settings' median
        times e^(spread·z), z a standard normal drawn from the seed (0 for a silent stepper)."""
        s = self.settings
        z = float(effect_rng(seed, "rig.stepper_noise").standard_normal())
        return s.stepper_noise_Pa * math.exp(s.stepper_noise_log_spread * z)

    def start_range_m(self, movement: Movement) -> tuple[float, float]:
        """(first, last) start position (m) on the texture's square for ``movement``: the contact patch (radius a at
        the movement's force) stays on the square from touchdown (a ≤ start) to the stroke's end (start + distance
        + a ≤ side).  Raises if the stroke and the patch do not fit on the square."""
        s = self.settings
        a = float(contact_patch_radius_m(movement.force_N, self.params.contact_radius_at_1N_m))
        travel = self.stage_travel_m(movement)
        last = s.texture_side_m - travel - a
        if last < a:
            raise ValueError(f"the stage's travel {travel * 1e3:.1f} mm (rig.distance_m = {s.distance_m} m; at "
                             f"{movement.velocity_m_per_s:g} m/s its ramps alone take v²/rig.stage_accel_m_per_s2 = "
                             f"{movement.velocity_m_per_s ** 2 / s.stage_accel_m_per_s2 * 1e3:.1f} mm) and the contact "
                             f"patch at {movement.force_N:g} N ({2 * a * 1e3:.1f} mm across) do not fit on "
                             f"rig.texture_side_m = {s.texture_side_m} m: shorten the stroke, raise the stage's "
                             f"acceleration or use a larger square")
        return a, last

    def stage_travel_m(self, movement: Movement) -> float:
        """How far (m) the stage moves the texture: the set distance, or more when the ramps up to the velocity and
        back take longer than the distance allows (v²/accel, no cruise)."""
        s = self.settings
        return max(s.distance_m, movement.velocity_m_per_s ** 2 / s.stage_accel_m_per_s2)

    def _lowered_ahead(self, texture: Texture, movement: Movement, seed: int,
                       start_position: float) -> tuple["_Run", float, dict, int]:
        """:meth:`_lowered` reading ahead; should the look-ahead misjudge the stop, again from the start with a
        snapshot before every window."""
        try:
            return self._lowered(texture, movement, seed, start_position, read_ahead=True)
        except _Overshot:
            run, reached, lowering, to_stop = self._lowered(texture, movement, seed, start_position, read_ahead=False)
            lowering["retried"] = True
            return run, reached, lowering, to_stop

    def _new_run(self, texture: Texture, seed: int, start_position: float) -> "_Run":
        """A trial's run at its start: the finger ``start_gap_m`` above ``texture`` at ``start_position`` (m),
        nothing read, no command given."""
        s = self.settings
        motion = CommandedMotion(texture, start_position_m=start_position, latency_s=s.latency_s,
                                 max_travel_m=s.distance_m + 0.01, skin=self.skin, depth_m=-s.start_gap_m)
        hum = [MountVibration(0.0, self.stepper_noise_Pa(seed))] if s.stepper_noise_Pa > 0 else []
        return _Run(Sensor(params=self.params, stimuli=[motion, *hum], channels_read=ch.DEFAULT_FRAME_NAMES,
                           fidelity=self.fidelity, seed=seed, noise=self.noise, block_s=s.chunk_s,
                           record_signals=("stage_force_N", "normal_force_N")),
                    motion, effect_rng(seed, "rig.motor_current"), s, self.spi_faults)

    def _lowered(self, texture: Texture, movement: Movement, seed: int, start_position: float,
                 read_ahead: bool) -> tuple["_Run", float, dict, int]:
        """The trial's run, its baseline read at rest, lowered until the controller gives the stop (at the arrival
        of the stop frame's batch) and read exactly up to that instant or to a point before it (nothing computed
        beyond); the PDC change (counts) it stopped at; what the emulator did to get there (windows, snapshots,
        frames computed and thrown away); and how many frames are still to be read until the stop is given (0: none).

        The controller decides on each batch's frames when the batch arrives; the emulator reads stretches of frames
        as if the finger keeps lowering (it does until the controller's stop acts) and checks the rule on each frame
        read.  A stretch that goes past the arrival of the stop frame's batch is thrown away: the run goes back to a
        snapshot taken before it, and the caller reads on from there to the arrival and gives the stop command then
        (the frames through the arrival are the same: the command acts a latency after it).
        With ``read_ahead``, stretches the stop is not expected in are read without a snapshot (see
        :func:`_next_stretch`); should the stop fall inside one anyway, :class:`_Overshot` is raised and the caller
        runs the lowering again without reading ahead (same result, slower)."""
        s = self.settings
        run = self._new_run(texture, seed, start_position)
        frame_s = run.frame / run.sampler.slot_rate_Hz
        batch = _batch_frames(s, frame_s)
        # baseline at rest, then lower until the PDC change reaches the target.  The lowering command, given when the
        # baseline's last batch arrives whatever it reads, is given now for that instant (nothing is computed yet),
        # so the baseline is read in one go with the first stretch of the lowering.
        baseline_frames = int(round(s.baseline_s / frame_s))
        if baseline_frames < 1:
            raise ValueError(f"rig.baseline_s = {s.baseline_s!r}: the PDC baseline needs at least one frame "
                             f"({frame_s * 1e3:.0f} ms)")
        first = _batch_end(baseline_frames - 1, batch)  # frames read before the lowering command
        run.motion.move_finger((run.sampler.next_slot + first * run.frame) / run.sampler.slot_rate_Hz,
                               s.lower_rate_m_per_s)
        target = movement.force_N / FORCE_PER_PDC_BIT_N
        window = max(1, int(round(s.speculation_s / frame_s)))
        budget = (int((s.start_gap_m + 0.01) / s.lower_rate_m_per_s / s.speculation_s) + 1) * window
        stats = {"windows": 0, "snapshots": 0, "frames_recomputed": 0, "frames_discarded": 0, "retried": False}
        # before any contact: the frames until the commanded load reaches the movement's force at the rig's own
        # calibration; the first stretch reads a share of them without a snapshot
        first_stretch = int(_AHEAD_FIRST_SHARE * _frames_to_load(run, movement.force_N, texture, budget, first)) \
            if read_ahead else 0
        if first_stretch < _MIN_WINDOW_FRAMES:  # too short to be worth it: the baseline alone
            run.read_exactly(first)
        baseline = None
        while True:
            if baseline is None and first_stretch < _MIN_WINDOW_FRAMES:
                baseline = _baseline(run.log.pdc_codes()[:baseline_frames])
            lowered = max(0, run.log.n_frames(run.frame) - first)  # frames read since the lowering command
            if lowered >= budget:
                raise RuntimeError(f"the finger never reached {movement.force_N} N (PDC +{target:.0f}) on "
                                   f"{texture.name}")
            if first_stretch >= _MIN_WINDOW_FRAMES:
                n, safe, first_stretch = first_stretch, True, 0
            else:
                change = _predicted_change(run, first, baseline, texture, budget - lowered)
                n, safe = _next_stretch(change, target, window, read_ahead)
            if not safe:  # a window that may hold the stop ends at a batch's arrival: no going back if it is the last
                n = _batch_end(first + lowered + n - 1, batch) - first - lowered
            n = min(n, budget - lowered)
            snapshot = None if safe else run.snapshot()
            stats["snapshots"] += int(snapshot is not None)
            stats["windows"] += 1
            before = first + lowered
            run.read_exactly(before + n - run.log.n_frames(run.frame))  # (with the baseline, the first time)
            pdc = run.log.pdc_codes()
            if baseline is None:
                baseline = _baseline(pdc[:baseline_frames])
            means = np.convolve(pdc, np.ones(s.pdc_average_frames) / s.pdc_average_frames, "full")[:pdc.size]
            over = np.flatnonzero(means[before:] - baseline >= target)
            if over.size:
                stop = before + int(over[0])  # the stop frame
                reached = float(means[stop] - baseline)
                k = _batch_end(stop, batch) - before  # frames from the stretch's start to the stop's batch arrival
                if k >= n:  # the arrival is at the stretch's end or after it: read on to it from here
                    return run, reached, stats, k - n
                # the stretch went past the arrival: back to before it; the caller reads from there to the arrival
                # and gives the stop command then (it acts a latency later, after all these frames)
                if snapshot is None:
                    raise _Overshot
                stats["frames_recomputed"] += k
                stats["frames_discarded"] += n - k
                return snapshot, reached, stats, k


def _baseline(pdc: np.ndarray) -> float:
    """The PDC baseline (counts): the mean of the baseline frames' readings the host took as good (a rejected one is
    NaN in ``pdc``); ValueError if the host rejected them all."""
    good = pdc[np.isfinite(pdc)]
    if not good.size:
        raise ValueError(f"the host rejected every PDC reading of the {pdc.size} baseline frames (parity errors or "
                         f"error words on the SPI bus): the rig has no resting PDC to lower against")
    return float(np.mean(good))


def _batch_frames(settings: RigSettings, frame_s: float) -> int:
    """Frames per batch the controller receives (``settings.batch_s`` over the frame's length ``frame_s``, s);
    raises unless the batch is a whole number of frames."""
    n = round(settings.batch_s / frame_s)
    if n < 1 or abs(n * frame_s - settings.batch_s) > 1e-9:
        raise ValueError(f"rig.batch_s = {settings.batch_s!r}: must be a whole number of frames "
                         f"({frame_s * 1e3:g} ms each), at least one")
    return n


def _batch_end(frame: int, batch: int) -> int:
    """Frames from the start of sampling to the arrival of the batch holding frame ``frame`` (0-based): batches of
    ``batch`` frames, aligned to the start of sampling."""
    return (frame // batch + 1) * batch


#: The longest block of grid samples the rig has the sensor compute at once after the stop (memory: ~0.5 MB per
#: signal; 7.4 s at the default profile's 8.8 kHz, 0.9 s at the reference profile's 70.4 kHz)
_MAX_BLOCK_SAMPLES = 2**16


class _Overshot(Exception):
    """The controller stopped inside a stretch read without a snapshot to go back to."""


#: Reading ahead while lowering (how far the emulator computes between checks; the controller's decisions and the
#: samples do not depend on it): the first stretch reads this share of the frames the contact law predicts at the
#: rig's calibration, without a snapshot; later ones end where the predicted PDC change comes within this many
#: counts, plus this share of the change still to go, of the target; a window with a snapshot then reads until the
#: predicted change passes the target by this many counts (PDC noise is ~0.5 count RMS; a second window costs a read
#: and a snapshot, a few frames more in the first cost little).  A stretch without a snapshot shorter than
#: ``_MIN_AHEAD_FRAMES`` is not read on its own: a read costs about as much as computing 40 frames at the default
#: profile, and the window with the snapshot takes its frames instead (over 60 trials: 3.0 reads and 1.0 snapshots
#: while lowering, against 4.75 and 1.08 with stretches down to 5 frames and a 2-count window margin).  The first
#: stretch's share: over the 357 trials of the library's 119 textures × D's three training movements (seed 1), 2.18
#: reads and 1.02 snapshots per trial while lowering, and 2 lowerings run again, at 0.85, against 2.85, 1.08 and 5 at
#: 0.6 and 2.08, 1.03 and 4 at 0.9 (the stop comes within a few % of the contact law's prediction; plastic canvas and
#: the furs are the textures where it does not); every code of the 357 trials the same at 0.6 and 0.85.
_AHEAD_FIRST_SHARE = 0.85
_AHEAD_MARGIN_COUNTS = 3.0
_AHEAD_MARGIN_SHARE = 0.3
_WINDOW_MARGIN_COUNTS = 4.0
_MIN_WINDOW_FRAMES = 5
_MIN_AHEAD_FRAMES = 40
_FIT_FRAMES = 30  # the PDC change is predicted from the last this many frames in contact


def _next_stretch(change: np.ndarray | None, target: float, window: int, read_ahead: bool) -> tuple[int, bool]:
    """The next stretch to read while lowering (frames), and whether the stop is not expected in it (it is then read
    without a snapshot), from the PDC change (counts) predicted for the frames ahead (None: not known yet)."""
    if change is None:
        return window, False
    if read_ahead:
        margin = _AHEAD_MARGIN_COUNTS + _AHEAD_MARGIN_SHARE * max(0.0, target - change[0])
        near = change >= target - margin
        if near.any() and int(np.argmax(near)) >= _MIN_AHEAD_FRAMES:
            return int(np.argmax(near)), True
    past = change >= target + _WINDOW_MARGIN_COUNTS
    if past.any():
        return min(window, max(_MIN_WINDOW_FRAMES, int(np.argmax(past)))), False
    return window, False


def _commanded_load(run: "_Run", t: np.ndarray, texture: Texture) -> np.ndarray:
    """The load (N) the contact law gives the depth planned for instants ``t`` (s) (texture relief aside)."""
    return contact_force_from_depth(run.motion.planned_depth_at(t), run.sensor.params, texture)


def _frames_to_load(run: "_Run", force_N: float, texture: Texture, horizon: int, after: int = 0) -> int:
    """Frames from ``after`` frames from now until the commanded load (:func:`_commanded_load`) reaches ``force_N``
    (N); ``horizon`` if not within that many frames."""
    t = run.now + (after + np.arange(horizon)) * run.frame / run.sampler.slot_rate_Hz
    reached = np.flatnonzero(_commanded_load(run, t, texture) >= force_N)
    return int(reached[0]) if reached.size else horizon


def _predicted_change(run: "_Run", first: int, baseline: float, texture: Texture, horizon: int) -> np.ndarray | None:
    """The PDC change (counts) expected in each of the next ``horizon`` frames if the finger keeps lowering, or None
    if it cannot be told yet: the PDC change of the last lowering frames in contact (read since frame ``first``),
    fitted as a straight line in the commanded load (the line takes up the texture's relief pressing in as the
    patch grows), along the commanded load of the frames ahead."""
    # (the commanded load grows while lowering, so the frames in contact are the last ones)
    last = max(first, run.log.n_frames(run.frame) - _FIT_FRAMES)
    load = _commanded_load(run, np.concatenate(run.log.cur_t)[last:], texture)
    change = run.log.pdc_codes()[last:] - baseline
    touching = load > 0  # (a reading the host rejected, NaN, leaves no line: None, windows read with snapshots)
    if np.count_nonzero(touching) < _FIT_FRAMES // 2 or np.ptp(load[touching]) == 0:  # too few, or no line to fit
        return None
    x, y = load[touching], change[touching]
    dx = x - x.mean()
    slope = float(dx @ (y - y.mean()) / (dx @ dx))  # least squares
    offset = float(y.mean() - slope * x.mean())
    if not slope > 0:
        return None
    t = run.now + np.arange(horizon) * run.frame / run.sampler.slot_rate_Hz
    return offset + slope * _commanded_load(run, t, texture)


class _Run:
    """Everything a trial's run holds — sensor, SPI side, host sampler, motion, current noise, log — as one
    object, so the controller can snapshot it (a deep copy) and go back."""

    def __init__(self, sensor: Sensor, motion: CommandedMotion, current_rng, settings: RigSettings,
                 spi_faults: tuple[SpiFaultWindow, ...] = ()):
        self.sensor, self.motion, self.current_rng, self.settings = sensor, motion, current_rng, settings
        self.spi_faults = spi_faults
        self.sampler = Sampler(SoftwarePeripheral(sensor))
        self.frame = len(self.sampler.sequence)
        self.log = _Log()

    def snapshot(self) -> "_Run":
        """A copy to go back to: everything that changes while the run goes is copied; what stays fixed for
        the whole trial (parameters, texture, skin, the texture's spatial tables, filter coefficients, the channel
        maps, the sensor's last sampling plan — replaced, never edited) is shared, and each random generator is
        copied through its state (a quarter of deepcopy's cost), which makes the copy several times cheaper; the rest
        is copied by :func:`_clone` (deepcopy's copy, in 60 % of its time).  The cost accounting (seconds per effect)
        is shared too: it counts all the work done, windows thrown away included."""
        sensor, port = self.sensor, self.sampler.peripheral
        shared = [sensor.params, sensor.fidelity, self.motion.texture, self.motion.skin, self.settings,
                  sensor.noise, sensor._slow_cost, sensor.graph.costs, *sensor.graph.costs.values(),
                  sensor.variant, sensor._node_of_channel, sensor._last_plan, self.sampler.sequence,
                  self.sampler.command_words, getattr(port, "variant", None), getattr(port, "recognized", None),
                  getattr(port, "provided", None), getattr(port, "provided_lut", None)]
        holders = [self, sensor.adc, sensor.thermal]
        for effect in sensor.graph.effects:
            holders.append(effect)
            for contact in getattr(effect, "_contacts", ()):
                shared += [contact["heights"], contact["slopes"], contact["radii"], contact.get("fluctuation")]
            sos = getattr(getattr(effect, "filter", None), "sos", None)
            if sos is not None:
                shared.append(sos)
        memo = {id(o): o for o in shared if o is not None}
        for holder in holders:
            for value in vars(holder).values() if holder is not None else ():
                if isinstance(value, np.random.Generator) and id(value) not in memo:
                    memo[id(value)] = _copy_generator(value)
        return _clone(self, memo)

    @property
    def now(self) -> float:
        """The next slot's instant (s)."""
        return self.sampler.next_slot / self.sampler.slot_rate_Hz

    def read_exactly(self, n_frames: int) -> None:
        """:meth:`read`, computing the sensor's grid in one block through the last instant these frames need
        and not beyond, so a command given right after still lies in the future of everything computed."""
        last_slot = self.sampler.next_slot + n_frames * self.frame - 1
        _, t_last, _ = self.sampler.slots(np.array([last_slot]))
        fs = self.sensor.fs
        needed = int(np.floor(t_last[0] * fs)) + 2  # grid samples through the last one interpolation reads
        computed = int(round(self.sensor.simulated_s * fs))
        block_n = self.sensor.block_n
        self.sensor.block_n = max(1, needed - computed)
        try:
            self.read(n_frames)
        finally:
            self.sensor.block_n = block_n

    def read(self, n_frames: int) -> None:
        """Read ``n_frames`` frames through SPI, with the stage current and the true load once per frame."""
        s = self.settings
        t_cur = (self.sampler.next_slot + np.arange(n_frames) * self.frame) / self.sampler.slot_rate_Hz
        ft = self.sensor.signal("stage_force_N", t_cur)
        self.log.load(t_cur, self.sensor.signal("normal_force_N", t_cur))
        self.log.current(t_cur, s.motor.current_A(ft, self.current_rng))
        for n_slots, faults in self._fault_parts(n_frames * self.frame):
            if faults is not None:
                self.sampler.peripheral.faults = faults
            self.log.samples(self.sampler.read(n_slots))

    def _fault_parts(self, n_slots: int) -> list[tuple[int, Faults | None]]:
        """The next ``n_slots`` slots as runs of slots under the same SPI faults (:class:`SpiFaultWindow`; a slot
        in none: no fault), each (slots, faults); one run, faults None (left as they are), without windows."""
        if not self.spi_faults:
            return [(n_slots, None)]
        t_cmd = self.sampler.slots(self.sampler.next_slot + np.arange(n_slots))[0]
        which = np.full(n_slots, -1)
        for i, w in enumerate(self.spi_faults):
            which[(t_cmd >= w.start_s) & (t_cmd < w.end_s)] = i
        starts = np.concatenate([[0], np.flatnonzero(np.diff(which)) + 1, [n_slots]])
        return [(int(b - a), self.spi_faults[which[a]].faults if which[a] >= 0 else Faults())
                for a, b in zip(starts[:-1], starts[1:])]


_ATOMIC = frozenset({int, float, bool, str, bytes, complex, type(None), range, type, np.float64, np.int64, np.bool_,
                     np.dtype})
_PLAIN: dict[type, bool] = {}  # per class: are its instances copied as deepcopy's default does (see _plain)
_PLAIN_SIZE = type("_Plain", (), {}).__basicsize__  # an instance of a class of Python attributes only


def _plain(cls: type) -> bool:
    """Whether ``copy.deepcopy`` copies instances of ``cls`` by its default route — ``cls.__new__(cls)`` given the
    deep copy of the original's ``__dict__`` — so :func:`_clone` may do the same directly: an instance of Python
    attributes only (object's ``__new__``, no ``__slots__`` but empty ones, no built-in base), no ``__deepcopy__``,
    no own pickling hooks, no ``copyreg`` entry."""
    if cls not in _PLAIN:
        default = all(getattr(cls, name, None) is getattr(object, name, None)
                      for name in ("__reduce_ex__", "__reduce__", "__getstate__", "__new__"))
        _PLAIN[cls] = (default and cls.__basicsize__ == _PLAIN_SIZE and cls not in copyreg.dispatch_table
                       and not hasattr(cls, "__deepcopy__") and not hasattr(cls, "__setstate__")
                       and not any(vars(c).get("__slots__") for c in cls.__mro__[:-1]))
    return _PLAIN[cls]


def _clone(x, memo: dict):
    """``copy.deepcopy(x, memo)``, the same copy (shared what ``memo`` holds, every array copied in its own memory
    order, identity kept within the copy), faster: lists, dicts, tuples, arrays and plain objects (:func:`_plain`)
    are walked here, immutable scalars and strings kept, anything else left to ``copy.deepcopy`` with the same
    memo."""
    i = id(x)
    if i in memo:
        return memo[i]
    cls = type(x)
    if cls in _ATOMIC:
        return x
    if cls is np.ndarray and x.dtype != object:
        y = memo[i] = x.copy(order="K")
    elif cls is list:
        y = memo[i] = []
        y.extend([v if type(v) in _ATOMIC else _clone(v, memo) for v in x])
    elif cls is dict:
        y = memo[i] = {}
        _clone_items(x, y, memo)
    elif cls is tuple:
        y = memo[i] = tuple([v if type(v) in _ATOMIC else _clone(v, memo) for v in x])
    elif _plain(cls) and hasattr(x, "__dict__"):
        y = memo[i] = cls.__new__(cls)
        _clone_items(x.__dict__, y.__dict__, memo)
    else:
        return copy.deepcopy(x, memo)
    return y


def _clone_items(source: dict, target: dict, memo: dict) -> None:
    """``source``'s items cloned (:func:`_clone`) into ``target``."""
    for k, v in source.items():
        target[k if type(k) in _ATOMIC else _clone(k, memo)] = v if type(v) in _ATOMIC else _clone(v, memo)


_ANY_SEED = np.random.SeedSequence(0)  # (a bit generator built from it is at once given another's state)


def _copy_generator(g: np.random.Generator) -> np.random.Generator:
    """A generator that draws what ``g`` would draw from here on (its bit generator's full state copied)."""
    bits = type(g.bit_generator)(_ANY_SEED)
    bits.state = g.bit_generator.state
    return np.random.Generator(bits)


class _Log:
    """What the rig recorded: samples as read, motor current, and the true normal load for the report.  PAC's and
    PDC's samples are also kept apart as they are read (what the controller and the recording use: no pass over
    every sample read so far at each check).

    A sample the host flags bad (its status: a parity error or an error word, :mod:`bench.running.sampler`) is
    dropped, and counted (:meth:`rejected`): the recording holds the good samples only (so the properties never see
    a bad one: a PAC sample missing where they look is a gap, which leaves roughness and fineness undefined rather
    than filtering across it), and the controller reads a rejected PDC frame as NaN (no reading: it decides on the
    good frames alone)."""

    def __init__(self):
        self.t, self.ch, self.code, self.cur_t, self.cur, self.load_N = [], [], [], [], [], []
        self.slots = 0  # samples read
        self.of = {ch.PAC: ([], []), ch.PDC: ([], [])}  # channel -> (instants, codes; NaN where rejected) read, per read
        self.bad: dict[tuple[int, int], int] = {}  # (channel, status) -> samples the host flagged so

    def load(self, t, newtons):
        self.load_N.append(newtons)

    def mean_load(self, t0: float, t1: float) -> float:
        """Mean true normal load (N) over [t0, t1], from the emulator's own force (not from codes)."""
        t, load = np.concatenate(self.cur_t), np.concatenate(self.load_N)
        return float(np.mean(load[(t >= t0) & (t <= t1)]))

    def samples(self, s):
        self.t.append(s.times)
        self.ch.append(s.channels)
        self.code.append(s.codes)
        self.slots += s.times.size
        bad = s.status != STATUS_OK
        for channel, (times, codes) in self.of.items():
            at = s.channels == channel
            times.append(s.times[at])
            codes.append(np.where(bad[at], np.nan, s.codes[at]) if bad.any() else s.codes[at])
        for channel, status in zip(s.channels[bad].tolist(), s.status[bad].tolist()):
            self.bad[(channel, status)] = self.bad.get((channel, status), 0) + 1

    def rejected(self) -> dict[str, dict[str, int]]:
        """The samples the host flagged bad, by channel name and status: ``{"PAC": {"parity error": 440}}``."""
        out: dict[str, dict[str, int]] = {}
        for (channel, status), n in sorted(self.bad.items()):
            out.setdefault(ch.CHANNEL_NAME.get(channel, f"ch{channel}"), {})[STATUS_NAMES[status]] = n
        return out

    def current(self, t, amps):
        self.cur_t.append(t)
        self.cur.append(amps)

    def _cat(self):
        """Every sample read: instants (s), channels, codes."""
        if not self.t:  # nothing read yet
            return np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.uint16)
        if len(self.t) > 1:
            self.t, self.ch, self.code = [np.concatenate(self.t)], [np.concatenate(self.ch)], [np.concatenate(self.code)]
        return self.t[0], self.ch[0], self.code[0]

    def _channel(self, channel: int) -> tuple[np.ndarray, np.ndarray]:
        """The instants (s) and codes of one channel's samples read (PAC or PDC)."""
        times, codes = self.of[channel]
        if len(times) > 1:
            times[:], codes[:] = [np.concatenate(times)], [np.concatenate(codes)]
        return (times[0], codes[0]) if times else (np.zeros(0), np.zeros(0, dtype=np.uint16))

    def pdc_codes(self) -> np.ndarray:
        return self._channel(ch.PDC)[1].astype(float)

    def n_frames(self, frame: int) -> int:
        return self.slots // frame

    def recording(self, contact_s, slide_start, slide_end, texture, movement, trial, seed) -> TrialRecording:
        """The trial's recording: the good PAC and PDC samples (a rejected one left out), the stage current, the
        phases (s) and what the trial was."""
        (pac_t, pac), (pdc_t, pdc) = (_good(*self._channel(c)) for c in (ch.PAC, ch.PDC))
        return TrialRecording(pac_t, pac, pdc_t, pdc, np.concatenate(self.cur_t),
                              np.concatenate(self.cur), contact_s, slide_start, slide_end, texture=texture,
                              force_N=movement.force_N, velocity_m_s=movement.velocity_m_per_s, trial=trial, seed=seed)


def _good(times: np.ndarray, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The samples of (instants, codes) the host took as good: a rejected one (NaN) left out."""
    if codes.dtype.kind != "f":  # (no sample rejected: the codes as read)
        return times, codes
    keep = np.isfinite(codes)
    return times[keep], codes[keep]

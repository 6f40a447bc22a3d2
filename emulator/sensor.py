"""The sensor: builds the effect graph a scene needs and answers "ADC code of channel c at instant t".

The grid physics advances in blocks (state carried between them) only as far as the latest
instant asked for; a short history is kept so instants can be interpolated between grid
samples.  Memory therefore stays bounded however long the run.
"""

from __future__ import annotations

import functools
import math
import time
import warnings
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from emulator import channels as ch
from emulator.adc import Adc
from emulator.effects import Block, Effect, build_graph
from emulator.extrinsic import MainsHum, MountNoise
from emulator.fidelity import Fidelity, profile
from emulator.friction import fluctuation_floor, stribeck_velocity_limit_m_per_s
from emulator.frontend import Stage1, Stage2, amplifier_noise, stage2_noise
from emulator.mechanics import FluidLeak, ForceCoupling, RestingPressure, VibrationCoupling
from emulator.params import SensorParams
from emulator.sliding import CommandedMotion, Slide, SlidingContact, commanded_load_N
from emulator.electrodes import (Contact, ElectrodeModel, electrode_number, electrode_positions_mm, nail_touch_problem,
                                 shear_direction, surface_point_mm, surface_point_over_mm)
from emulator.stimuli import (AmbientStep, ContactForce, ForceStimulus, HeaterFailure, MountVibration, PowerOn,
                              OutsideModelWarning, PressureCalibrator, SphereDrop, Touch, Vibration,
                              PLACED_CONTACT_MIN_STEPS, calibration_pressure, contact_place, contact_span,
                              drop_depth_problem, placed_contact_too_short, skin_displacement, touch_slip_problem)
from emulator.skin import contact_patch_area_m2
from emulator.thermal import ThermalContact, ThermalEvents, ThermalModel, material, steady_state
from emulator.transducer import Bridge, CoreTemperature, johnson_noise

#: Which grid signal each pressure channel converts.
CHANNEL_NODE = {ch.PAC: "pac_V", ch.PDC: "pdc_V"}
#: Kinds of channel in Sensor.analog (grid nodes are 0..len(nodes)-1).
KIND_TDC, KIND_TAC, KIND_ELECTRODE, KIND_NOT_READ = 100, 101, 102, -1
FAULT_NAMES = ("electrode_open", "electrode_short", "mux_stuck", "thermistor", "heater_failed", "fluid_leak_mL_per_min",
               "fluid_leak_start_s")


def _check_fault_values(faults: dict) -> None:
    """Refuse fault values that would be silently misread (a scene's [faults] is checked the same way when
    loaded): the thermistor's kind, the heater's flag and the electrode lists; electrode numbers and the leak are
    checked by their models."""
    if faults.get("thermistor") not in (None, "open", "short"):
        raise ValueError(f"faults.thermistor = {faults['thermistor']!r}: must be \"open\" or \"short\"")
    if not isinstance(faults.get("heater_failed", False), (bool, np.bool_)):
        raise ValueError(f"faults.heater_failed = {faults['heater_failed']!r}: must be True or False")
    for key in ("electrode_open", "electrode_short"):
        if key in faults and not isinstance(faults[key], (list, tuple, set, frozenset, np.ndarray)):
            raise ValueError(f"faults.{key} = {faults[key]!r}: must be a list of electrode numbers, e.g. [3]")


def _as_lists(faults: dict) -> dict:
    """``faults`` with a set of electrode numbers given as a list, in order (each electrode's fault is its own, so
    a set says as much as a list; a list is what records and scenes hold)."""
    def listed(v):
        try:
            return sorted(v, key=float)
        except (TypeError, ValueError):
            return list(v)  # (a value that is no number is named by the electrode model's check)
    return {k: listed(v) if isinstance(v, (set, frozenset)) else v for k, v in faults.items()}


@dataclass(frozen=True)
class NoiseSources:
    """Switches for every noise source (all on = the real sensor at rest)."""

    johnson: bool = True
    amplifier: bool = True
    mains_hum: bool = True
    adc: bool = True
    spi_coupling: bool = True
    thermistor: bool = True

    @classmethod
    def none(cls) -> "NoiseSources":
        """Every noise source off (quantization remains: it is what an ADC does)."""
        return cls(False, False, False, False, False, False)



@functools.lru_cache(maxsize=64)
def _frame_plan(node_of_channel: bytes, n_nodes: int, channels: bytes) -> tuple:
    """:meth:`Sensor._plan` of the int64 ``channels`` (bytes) for a sensor whose channel map (int64 per channel
    index, bytes) and number of grid nodes are given: remembered, since a rig builds a sensor per trial and its
    host reads the same batches every trial."""
    channels = np.frombuffer(channels, dtype=np.int64)
    if channels.min() < 0 or channels.max() > 63:
        raise ValueError("channel indices must be 0..63")
    node_of = np.frombuffer(node_of_channel, dtype=np.int64)[channels]
    if np.any(node_of < 0):
        bad = int(channels[np.flatnonzero(node_of < 0)[0]])
        raise ValueError(f"channel {ch.CHANNEL_NAME.get(bad, bad)} was not declared in channels_read")
    nodes = []
    for node_id in range(n_nodes):
        sel = node_of == node_id
        if sel.all():
            nodes.append((node_id, None))
        elif sel.any():
            nodes.append((node_id, np.flatnonzero(sel)))
    thermal = [(column, np.flatnonzero(node_of == kind)) for kind, column in ((KIND_TDC, 1), (KIND_TAC, 2))]
    at = np.flatnonzero(node_of == KIND_ELECTRODE)
    electrodes = (electrode_number(channels[at]), at) if at.size else None
    for a in [w for _, w in nodes if w is not None] + [w for _, w in thermal] + list(electrodes or ()):
        a.flags.writeable = False  # shared by every sensor asking for these channels
    return nodes, [(c, w) for c, w in thermal if w.size], electrodes


_ALL = np.zeros(0, dtype=np.int64)  # (_interpolate: every position)

#: the most grid samples one physics block holds: a longer ``block_s`` is computed in blocks of this many (results
#: do not depend on the block size, and memory stays ~20 MB whatever block is asked for: 3.7 s at the reference grid)
MAX_BLOCK_SAMPLES = 2**18


#: the physics block a sensor computes at once unless told otherwise (s; results do not depend on it)
DEFAULT_BLOCK_S = 2.0


def _block_samples(block_s: float, fs: float) -> int:
    """Grid samples per physics block for a block of ``block_s`` s (finite, > 0: checked by :class:`Sensor`) on a
    grid of ``fs`` Hz: at least 1, at most :data:`MAX_BLOCK_SAMPLES`."""
    return max(1, int(round(min(block_s * fs, MAX_BLOCK_SAMPLES))))  # (capped before rounding: 1e308 s × fs is inf)


@njit(cache=True)
def _grid_positions(times, fs):
    """Each instant (s) on the grid of rate ``fs`` (Hz): index i = ⌊t·fs⌋ and fraction t·fs − i, and the least and
    greatest index; (-1, -1) for those if an instant is negative or not finite (or beyond the grid's range)."""
    i = np.empty(times.size, dtype=np.int64)
    frac = np.empty(times.size)
    i_min, i_max = np.iinfo(np.int64).max, -1
    for p in range(times.size):
        x = times[p] * fs
        if not (x >= 0.0 and x < 2.0**62):
            return i, frac, -1, -1
        i[p] = int(math.floor(x))
        frac[p] = x - i[p]
        i_min, i_max = min(i_min, i[p]), max(i_max, i[p])
    return i, frac, i_min, i_max


@njit(cache=True)
def _interpolate(h, k, frac, at, out):
    """Linear interpolation between grid samples ``h``: out[p] = h[k]·(1 − frac) + h[k + 1]·frac at each position p
    of ``at`` (empty: every position), with k = ``k[p]`` and frac = ``frac[p]``."""
    n = at.size if at.size else k.size
    for q in range(n):
        p = at[q] if at.size else q
        out[p] = h[k[p]] * (1.0 - frac[p]) + h[k[p] + 1] * frac[p]


class Sensor:
    """One emulated BioTac.

    Parameters
    ----------
    params : SensorParams
    stimuli : force stimuli (taps, presses, sphere drops), :class:`Vibration` and :class:`PressureCalibrator`
    channels_read : channel names or indices the host will sample; decides which effects are built
    fidelity : profile name or :class:`Fidelity`
    seed : scene seed; every random effect draws from a stream keyed by (seed, effect name)
    noise : which noise sources are on
    block_s : physics block length in s, finite and > 0 (results do not depend on it; a block longer than
        :data:`MAX_BLOCK_SAMPLES` grid samples is computed in pieces of that many)
    start_s : the instant (s) at which the sensor starts, settled at rest; earlier instants do not exist
    faults : sensor faults: ``electrode_open``/``electrode_short`` (lists of electrode numbers), ``mux_stuck``
        (electrode number), ``thermistor`` ("open" or "short"), ``heater_failed`` (True), ``fluid_leak_mL_per_min``
        (mL/min) from ``fluid_leak_start_s`` (s, default 0): a leak (:class:`emulator.mechanics.FluidLeak`)
    record_signals : grid signals besides the channels' nodes to keep for :meth:`signal` (e.g.
        ``"tangential_force_N"`` for a rig's stage current, ``"contact_force_N"`` for the true normal load)
    variant : ``"biotac"`` (19 electrodes, the dissertation's sensor) or ``"biotac-sp"`` (24 electrodes,
        E20..E24 at channel indices 36..40); see :mod:`emulator.channels`
    """

    def __init__(self, params: SensorParams | None = None, stimuli=(), channels_read=("PAC", "PDC"),
                 fidelity: str | Fidelity = "default", seed: int = 0, noise: NoiseSources = NoiseSources(),
                 block_s: float = DEFAULT_BLOCK_S, start_s: float = 0.0, faults: dict | None = None, record_signals=(),
                 variant: str = ch.DEFAULT_VARIANT):
        self.variant = ch.variant(variant)  # ValueError naming the allowed variants
        if params is not None and not isinstance(params, SensorParams):
            raise TypeError(f"params = {params!r}: give a SensorParams, e.g. SensorParams().replace("
                            f"inflation_volume_mL=0.6) (emulator.params)")
        if not (isinstance(block_s, (int, float, np.integer, np.floating)) and not isinstance(block_s, bool)
                and np.isfinite(block_s) and block_s > 0):  # (numpy numbers too, as the seed takes them)
            raise ValueError(f"block_s = {block_s!r}: must be a finite number > 0 (the physics block, s)")
        if not (isinstance(seed, (int, np.integer, float, np.floating)) and not isinstance(seed, bool)
                and np.isfinite(seed) and float(seed).is_integer() and seed >= 0):  # 3262.0 is a whole number
            raise ValueError(f"seed = {seed!r}: must be a whole number ≥ 0")
        self.params = params or SensorParams()
        self.faults = dict(faults or {})
        unknown_faults = set(self.faults) - set(FAULT_NAMES)
        if unknown_faults:
            raise ValueError(f"unknown sensor fault(s): {', '.join(sorted(unknown_faults))}; known: {', '.join(FAULT_NAMES)}")
        _check_fault_values(self.faults)
        self.faults = _as_lists(self.faults)
        self.leak = self._fluid_leak()
        if not (np.isfinite(start_s) and start_s >= 0):
            raise ValueError(f"start_s = {start_s!r}: must be a finite instant ≥ 0 s")
        self._start_s = float(start_s)
        stimuli = list(stimuli)
        self.stimuli = tuple(stimuli)  # what the sensor feels, as given (reports say it; nothing reads it back)
        self.fidelity = profile(fidelity) if isinstance(fidelity, str) else fidelity
        self.seed = int(seed)
        self.noise = noise
        self.fs = self.fidelity.grid_Hz
        self.block_n = _block_samples(block_s, self.fs)
        self.channels_read = sorted({int(c) if isinstance(c, (int, np.integer)) else ch.channel_index(c)
                                     for c in channels_read})
        unknown = [c for c in self.channels_read if c not in self.variant.sampled_channels]
        if unknown:
            raise ValueError(f"channel {ch.variant('biotac-sp').channel_name.get(unknown[0], unknown[0])} "
                             f"(index {unknown[0]}) is not a sampled channel of a {self.variant.name!r} sensor "
                             f"(E1..E{self.variant.n_electrodes}, PAC, PDC, TAC, TDC)")
        reads_electrodes = any(c >= ch.ELECTRODE_FIRST for c in self.channels_read)
        for st in stimuli:  # whether or not an electrode is read: the place must be on this sensor
            place = contact_place(st)
            if place is not None and place[0] is not None and place[0] not in self.variant.channel_index:
                raise ValueError(f"{type(st).__name__.lower()} over electrode {place[0]!r}: a {self.variant.name!r} "
                                 f"sensor has E1..E{self.variant.n_electrodes}")
            why = place is not None and place[0] is None and nail_touch_problem(place[2], self.params)
            if why:
                raise ValueError(f"{type(st).__name__}.angle_deg = {place[2]!r}: {why}")
            if isinstance(st, Touch) and (why := touch_slip_problem(st)):
                warnings.warn(f"Touch at {st.start_s!r} s: tangential_N = {st.tangential_N!r} N {why} (a scene "
                              f"refuses it; its codes here are the model's extrapolation)", OutsideModelWarning,
                              stacklevel=2)
            if placed_contact_too_short(st, self.fidelity.electrode_rate_Hz) and reads_electrodes:
                rate, (span_s, fields) = self.fidelity.electrode_rate_Hz, contact_span(st)
                warnings.warn(f"{type(st).__name__} at {st.start_s!r} s: {span_s * 1e3:g} ms ({fields}) "
                              f"at a place is shorter than two steps of the electrodes' model at fidelity "
                              f"{self.fidelity.name!r} ({rate:.0f} Hz: at least "
                              f"{PLACED_CONTACT_MIN_STEPS * 1e3 / rate:g} ms): its dent depends on where the steps "
                              f"fall (a scene refuses it)", OutsideModelWarning, stacklevel=2)
            if isinstance(st, (Slide, CommandedMotion)) and (why := self._friction_passivity_problem(st.texture)):
                warnings.warn(f"{type(st).__name__} at {st.start_s!r} s: {why} (a library refuses such a texture; "
                              f"its codes here are the model's extrapolation)", OutsideModelWarning, stacklevel=2)
            if isinstance(st, SphereDrop) and (why := drop_depth_problem(st, self.params)):
                warnings.warn(f"SphereDrop at {st.time_s!r} s: {why} (a scene refuses it; its codes here are the "
                              f"model's extrapolation)", OutsideModelWarning, stacklevel=2)
        self.nodes = sorted({CHANNEL_NODE[c] for c in self.channels_read if c in CHANNEL_NODE})
        self.record_signals = tuple(record_signals)
        self.thermal, self.thermal_steady = self._thermal_model(stimuli)
        motions = [s for s in stimuli if isinstance(s, (Slide, CommandedMotion))]
        f = self.fidelity
        # built only for scenes that slide, and only if something reads the grid: the pressure channels, a recorded
        # signal or the electrodes (a sliding motion's pad reads its forces); TDC and TAC alone never need it (the
        # thermal contact takes the nominal load)
        grid_read = bool(self.nodes or self.record_signals or any(c >= ch.ELECTRODE_FIRST for c in self.channels_read))
        self.sliding = (SlidingContact(motions, self.params, self.fs, f.sliding_dx_m, f.friction_substeps,
                                       f.patch_radii, self.seed, ridges=f.ridges)
                        if motions and grid_read else None)
        self.electrodes = self._electrode_model(stimuli)
        # a sliding motion's electrode contact reads the sliding contact's forces: it runs when electrodes are read
        fed = self.electrodes is not None and self.sliding is not None
        self.graph = build_graph(self._candidate_effects(stimuli),
                                 set(self.nodes) | set(self.record_signals) | ({"normal_force_N"} if fed else set()))
        self.resting = self.graph.settle()
        self.adc = Adc(self.params, self.seed, noise=noise.adc, spi_coupling=noise.spi_coupling)
        # per channel index: which grid node or slow model it converts
        self._node_of_channel = np.full(64, KIND_NOT_READ, dtype=np.int64)
        for c in self.channels_read:
            if c in CHANNEL_NODE:
                self._node_of_channel[c] = self.nodes.index(CHANNEL_NODE[c])
            elif c == ch.TDC:
                self._node_of_channel[c] = KIND_TDC
            elif c == ch.TAC:
                self._node_of_channel[c] = KIND_TAC
            else:
                self._node_of_channel[c] = KIND_ELECTRODE
        self._chunks: dict[str, list[np.ndarray]] = {n: [] for n in self._kept}
        self._slow_cost = {"thermal": 0.0, "electrodes": 0.0}  # wall time of the slow models, s
        # grid index of the first retained sample: the one at or before the start, so that the start instant itself
        # can be interpolated (ceil refused it whenever start_s·fs is not an integer, e.g. 0.07 s·8800 Hz in floats)
        self._buf_n0 = int(np.floor(start_s * self.fs))
        self._computed = self._buf_n0  # next grid index to compute
        self._last_plan = None  # (channels, plan) of the last analog() call (see _plan)

    # --- construction --------------------------------------------------------------
    def _candidate_effects(self, stimuli) -> list[Effect]:
        p, fs, disc, f = self.params, self.fs, self.fidelity.discretization, self.fidelity
        forces = [s for s in stimuli if isinstance(s, ForceStimulus)]
        vibrations = [s for s in stimuli if isinstance(s, Vibration)]
        calibrations = [s for s in stimuli if isinstance(s, PressureCalibrator)]
        mounts = [s for s in stimuli if isinstance(s, MountVibration) and s.rms_Pa > 0]
        other = [s for s in stimuli if not isinstance(s, (ForceStimulus, Vibration, PressureCalibrator, PowerOn,
                                                         AmbientStep, HeaterFailure, Slide, CommandedMotion,
                                                         MountVibration))]
        if other:
            raise TypeError(f"not a stimulus: {other[0]!r}")
        for v in vibrations:
            top = max(v.f_start_Hz, v.f_stop_Hz or 0.0)
            if top >= 0.45 * fs:
                raise ValueError(f"vibration at {top:.0f} Hz needs a finer grid than {fs:.0f} Hz "
                                 f"(fidelity '{f.name}'); use a higher fidelity profile")
        effects: list[Effect] = []
        if forces:
            effects.append(ContactForce(forces))
        if vibrations:
            effects.append(skin_displacement(vibrations))
        if calibrations:
            effects.append(calibration_pressure(calibrations))
        if mounts:
            effects.append(MountNoise(mounts, fs, self.seed))
        if self.sliding is not None:
            effects.append(self.sliding)
        dynamic = self.thermal is not None
        if dynamic:
            effects.append(CoreTemperature(self.thermal))
        effects += [RestingPressure(p, self.leak, self._start_s), ForceCoupling(p, fs, disc, self.leak),
                    VibrationCoupling(p, fs, disc, self.leak),
                    Bridge(p, fs, duct_resonance=f.duct_resonance, thermal=dynamic,
                           settled_temperature_C=None if dynamic else self.thermal_steady[0])]
        if self.noise.johnson:
            effects.append(johnson_noise(p, fs, self.seed))
        if self.noise.amplifier:
            effects.append(amplifier_noise(p, fs, self.seed))
        if self.noise.mains_hum:
            effects.append(MainsHum(p, self.seed))
        effects.append(Stage1(p, fs, disc))
        own_noise = f.stage2_noise and self.noise.amplifier
        if own_noise:
            effects.append(stage2_noise(p, fs, self.seed))
        effects.append(Stage2(p, fs, disc, own_noise=own_noise))
        return effects

    def _fluid_leak(self) -> FluidLeak | None:
        """The leak the faults name (None: no leak; a start without a rate is refused)."""
        rate = self.faults.get("fluid_leak_mL_per_min")
        if rate is None:
            if "fluid_leak_start_s" in self.faults:
                raise ValueError("fluid_leak_start_s is set but fluid_leak_mL_per_min is not: a leak needs its rate")
            return None
        return FluidLeak(rate, self.faults.get("fluid_leak_start_s", 0.0))

    def _thermal_model(self, stimuli):
        """The thermal network when something thermal happens; otherwise the settled steady state (shortcut)."""
        p = self.params
        contacts = []
        for s in stimuli:
            if isinstance(s, Touch) and s.material is not None:
                temp = p.ambient_temperature_C if s.object_temperature_C is None else s.object_temperature_C
                contacts.append(ThermalContact(s.start_s, s.end_s, material(s.material), temp,
                                               np.pi * (s.indenter_radius_mm * 1e-3) ** 2))
            elif isinstance(s, Slide):  # the texture at room temperature, over the patch at the slide's force
                contacts.append(ThermalContact(s.start_s, s.end_s, material(s.texture.material),
                                               p.ambient_temperature_C, contact_patch_area_m2(s.force_N, p.contact_radius_at_1N_m)))
            elif isinstance(s, CommandedMotion):  # a rig's finger: touching while its commanded depth is > 0,
                # read as the run goes (a partial, not a closure: a copy of the sensor, as the rig's snapshot, reads
                # the copied motion)
                contacts.append(ThermalContact(s.start_s, s.end_s, material(s.texture.material),
                                               p.ambient_temperature_C,
                                               load_N=functools.partial(commanded_load_N, s, p)))
        power_on = [s.at_s for s in stimuli if isinstance(s, PowerOn)]
        steps = tuple(sorted((s.at_s, s.temperature_C) for s in stimuli if isinstance(s, AmbientStep)))
        failures = [s.at_s for s in stimuli if isinstance(s, HeaterFailure)]
        events = ThermalEvents(contacts, power_on[0] if power_on else None, steps, failures[0] if failures else None)
        thermal_read = any(c in (ch.TDC, ch.TAC) for c in self.channels_read)
        pressure_read = bool(self.nodes)
        if events.any and (thermal_read or pressure_read):
            return ThermalModel(p, events, self.seed, self.faults, noise=self.noise.thermistor), None
        return None, steady_state(p, self.faults)

    def _friction_passivity_problem(self, texture) -> str | None:
        """Why this sensor's friction element is not passive on ``texture`` (None if it is): its Stribeck velocity
        (m/s) past :func:`emulator.friction.stribeck_velocity_limit_m_per_s` at the sensor's bristle damping."""
        sigma1, tex = self.params.bristle_damping_per_N, texture
        limit = stribeck_velocity_limit_m_per_s(tex.mu_kinetic, sigma1, tex.friction_fluctuation_rms)
        if tex.stribeck_velocity_m_per_s <= limit * (1.0 + 1e-12):
            return None
        return (f"texture {tex.number} ({tex.name}): stribeck_velocity_m_per_s = {tex.stribeck_velocity_m_per_s!r} "
                f"is past {limit:.4g} m/s, the most with which the friction stays passive at mu_kinetic = "
                f"{tex.mu_kinetic!r} and bristle_damping_per_N = {sigma1:g} s/m (σ1·v_s/√(2e) ≤ 4·µk × "
                f"{fluctuation_floor(tex.friction_fluctuation_rms):g}): at a slip's onset it could give energy back")

    def _electrode_model(self, stimuli):
        """The electrode model, only if the host reads an electrode."""
        if not any(c >= ch.ELECTRODE_FIRST for c in self.channels_read):
            return None
        positions = electrode_positions_mm(self.variant.name)
        contacts = []
        for s in stimuli:
            if isinstance(s, (Slide, CommandedMotion)):
                contacts.append(self._pad_contact(s))
                continue
            place = contact_place(s)  # a touch; a tap or press given a place (none: only the fluid feels it)
            if place is None:
                continue
            electrode, x_mm, angle_deg = place
            if electrode is not None:  # (one of this sensor's: checked when it was made)
                centre = surface_point_over_mm(positions[self.variant.channel_index[electrode] - ch.ELECTRODE_FIRST])
            else:
                centre = surface_point_mm(x_mm, angle_deg)
            sheared = isinstance(s, Touch)
            direction = shear_direction(centre, s.shear_angle_deg if sheared else 0.0,
                                        None if electrode is not None else angle_deg)
            contacts.append(Contact(centre, s.indenter_radius_mm, s.force,
                                    s.tangential_N / s.force_N if sheared and s.force_N else 0.0, tuple(direction),
                                    s.start_s, s.end_s))
        return ElectrodeModel(self.params, contacts, self.faults, self.fidelity.discretization,
                              self.fidelity.electrode_rate_Hz, positions=positions, leak=self.leak)

    def _pad_contact(self, motion) -> Contact:
        """The electrodes' contact of a sliding motion: the ventral pad (x = −5 mm, angle 0) on the texture, pressed
        and sheared by the forces the sliding contact computes on the grid — its normal load and its friction force,
        signed, along the stage's axis (+x) — handed over at the electrode rate by a :class:`ForceFeed` (the mean
        over each electrode period).  While the stage holds still the friction, and so the shear, is zero; at slip
        the shear comes with the friction's ramp, stick-slip and fluctuations.  ``normal_N`` (the nominal load: the
        scripted force, or the contact law of a rig's commanded depth, a partial so that a copied sensor reads the
        copied motion) gives only the load held before t = 0."""
        nominal = (motion.normal_force_N if isinstance(motion, Slide)
                   else functools.partial(commanded_load_N, motion, self.params))
        feed = self.sliding.force_feed(motion, self.fidelity.electrode_rate_Hz)
        return Contact(surface_point_mm(-5.0, 0.0), self.params.contact_radius_at_1N_m * 1e3, nominal, 0.0,
                       (1.0, 0.0, 0.0), motion.start_s, motion.end_s, planned=False, forces=feed)

    # --- time advance ---------------------------------------------------------------
    def _advance_through(self, n_last: int, keep_from: int, exact: bool = False) -> None:
        """Compute the grid through index ``n_last``, retaining nothing before ``keep_from``; ``exact``: not beyond
        it (the last block is cut short), so a rig's command given next still lies ahead of everything computed."""
        while self._computed <= n_last:
            n = min(self.block_n, n_last + 1 - self._computed) if exact else self.block_n
            block = Block(self._computed, n, self.fs)
            signals = self.graph.run(block)
            self._computed += block.n
            if self._computed <= keep_from:  # a whole block nobody will ask for: do not keep it
                self._buf_n0 = self._computed
                for node in self._kept:
                    self._chunks[node] = []
                continue
            for node in self._kept:
                self._chunks[node].append(signals[node] if node in signals else np.zeros(block.n))
        self._trim(keep_from)

    def _history(self, node: str) -> np.ndarray:
        chunks = self._chunks[node]
        if len(chunks) > 1:
            chunks[:] = [np.concatenate(chunks)]
        return chunks[0] if chunks else np.empty(0)

    def _trim(self, keep_from: int) -> None:
        drop = keep_from - self._buf_n0
        if drop <= 0:
            return
        for node in self._kept:
            h = self._history(node)
            self._chunks[node] = [h[drop:]]
        self._buf_n0 = keep_from

    @property
    def _kept(self) -> tuple[str, ...]:
        """Grid signals whose recent history is kept: the channels' nodes and ``record_signals``."""
        return tuple(self.nodes) + tuple(s for s in self.record_signals if s not in self.nodes)

    def signal(self, name: str, times) -> np.ndarray:
        """Value of a recorded grid signal (one of ``record_signals``, SI units) at ``times`` (s, in time order),
        linearly interpolated: the world beside the sensor, e.g. the tangential force a rig's stage feels."""
        if name not in self.record_signals:
            raise ValueError(f"signal {name!r} was not declared in record_signals {self.record_signals}")
        times = np.asarray(times, dtype=float)
        if times.size == 0:
            return np.empty(0)
        i, frac, i_min, i_max = _grid_positions(times.reshape(-1), self.fs)
        if i_min < self._buf_n0:
            raise ValueError(f"instant {times.min():.6f} s is older than the retained history")
        self._advance_through(i_max + 1, keep_from=self._buf_n0)
        out = np.empty(times.shape)
        _interpolate(self._history(name), i - self._buf_n0, frac, _ALL, out.reshape(-1))
        return out

    @property
    def simulated_s(self) -> float:
        return self._computed / self.fs

    # --- sampling -------------------------------------------------------------------
    def _plan(self, channels: np.ndarray) -> tuple:
        """Where each kind of channel sits in ``channels`` (validated): a tuple of (grid node index, positions or
        None for all) per grid node read, (column, positions) for TDC and TAC, and (electrode numbers, positions).
        The host asks for the same frame batch after batch: the last plan is kept and reused for an equal array
        (and plans are remembered across sensors, :func:`_frame_plan`)."""
        last = self._last_plan
        if last is not None and last[0].shape == channels.shape and np.array_equal(last[0], channels):
            return last[1]
        plan = _frame_plan(self._node_of_channel.tobytes(), len(self.nodes), channels.tobytes())
        self._last_plan = (channels.copy(), plan)
        return plan

    def analog(self, channels, times) -> np.ndarray:
        """Analog value (V) at the ADC input for each (channel index, instant in s); no ADC effects."""
        channels = np.asarray(channels, dtype=np.int64)
        times = np.asarray(times, dtype=float)
        out = np.empty(times.shape)
        if times.size == 0:
            return out
        i, frac, i_min, i_max = _grid_positions(times.reshape(-1), self.fs)
        if i_min < 0:
            raise ValueError("sample instants must be finite and ≥ 0 s")
        if times.min() < self._start_s - 1e-9:  # (the grid sample before the start is kept only to interpolate)
            raise ValueError(f"instant {times.min():.6f} s is before the sensor's start (start_s = {self._start_s:g} "
                             f"s): earlier instants do not exist")
        nodes, thermal, electrodes = self._plan(channels)
        if i_min < self._buf_n0:
            raise ValueError(f"instant {times.min():.6f} s is older than the retained history "
                             f"(from {self._buf_n0 / self.fs:.6f} s): ask for instants in time order")
        # (a grid that keeps no signal serves at most the electrodes' feed: computed no further than asked)
        self._advance_through(i_max + 1, keep_from=i_min, exact=not self._kept)
        if electrodes is not None:  # a contact fed from the grid (a sliding motion's) needs the grid through the
            # electrode step after the latest instant: computed that far and no further
            self._advance_through(self.electrodes.grid_needed(float(times.reshape(-1)[electrodes[1]].max())),
                                  keep_from=i_min, exact=True)
        k = i - self._buf_n0
        for node_id, at in nodes:
            _interpolate(self._history(self.nodes[node_id]), k, frac, _ALL if at is None else at, out.reshape(-1))
        t0 = time.perf_counter()
        for column, at in thermal:
            out[at] = (self.thermal.value_at(times[at], column) if self.thermal is not None
                       else self.thermal_steady[column])
        t1 = time.perf_counter()
        if electrodes is not None:
            number, at = electrodes
            out[at] = self.electrodes.sample(number, times[at])
        self._slow_cost["thermal"] += t1 - t0
        self._slow_cost["electrodes"] += time.perf_counter() - t1
        self._trim(i_max)
        if self.thermal is not None:
            self.thermal.forget_before(min(times.max(), self._buf_n0 / self.fs))
        return out

    def analog_trace(self, channel, times, chunk_s: float = 1.0) -> np.ndarray:
        """Analog value (V) of one channel at increasing ``times`` (s), asked for ``chunk_s`` of instants at a
        time so the retained history stays short however long the trace."""
        times = np.asarray(times, dtype=float)
        index = channel if isinstance(channel, (int, np.integer)) else ch.channel_index(channel)
        span = float(times[-1] - times[0]) if times.size else 0.0
        parts = np.array_split(times, max(1, int(np.ceil(span / chunk_s))))
        return np.concatenate([self.analog(np.full(part.size, index), part) for part in parts])

    def sample(self, channels, times, bus_active=None) -> np.ndarray:
        """12-bit codes for each (channel index, instant in s), converted in the given order."""
        v = self.analog(channels, times)
        return self.adc.convert(v, bus_active, where="the ADC input", channels=channels)

    # --- reporting ------------------------------------------------------------------
    def effects_report(self) -> list[dict]:
        """The effects that ran, what they consumed and produced, and what they cost."""
        sim_s = max(self.simulated_s, 1e-12)
        rows = []
        for cost in self.graph.costs.values():
            d = asdict(cost)
            d["seconds_per_simulated_s"] = cost.seconds / sim_s
            rows.append(d)
        slow = (("thermal_network", self.thermal is not None, "thermal network at 100 Hz -> TDC, TAC, core temperature",
                 "thermal"),
                ("thermal_steady_state", self.thermal is None and any(c in (ch.TDC, ch.TAC) for c in self.channels_read),
                 "settled thermal state (shortcut: nothing thermal happens)", "thermal"),
                ("electrodes", self.electrodes is not None, "contact geometry -> fluid gaps -> impedance -> mux",
                 "electrodes"))
        for name, built, what, key in slow:
            if built:
                rows.append({"name": name, "description": what, "consumes": (), "produces": (),
                             "seconds": self._slow_cost[key], "samples": 0,
                             "seconds_per_simulated_s": self._slow_cost[key] / sim_s})
        return rows

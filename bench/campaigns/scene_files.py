"""Your own scenes in the fault campaign: a scene file (as ``biotac-bench run`` takes it) or a shipped scene,
given to ``campaign --scenes`` as a path or a name ending in ``.toml``, whose sensor 1 feels the scene in every
fault case.

What a scene contributes to a case: sensor 1's stimuli, unit, variant, parameters, skin, noise switches and
fidelity profile (the sensor is built as a scene run builds it: :func:`bench.hosts.scene_sensors.sensors_from_scene`);
the campaign's seed replaces the scene's ``[scene] seed``; a fault's second sensor is sensor 1's twin at rest, as in a
scene.  A case streams the scene's whole duration and :data:`LEAK_TAIL_FRAMES` frames more, at least the
:data:`CASE_FRAMES` frames of a built-in scene's case; a scene lasts at most :data:`CASE_MAX_S`.

What the campaign cannot honour is refused before anything runs, naming the file and the field
(:func:`campaign_scene`): several sensors, sensor faults of the scene's own (the campaign injects its own), a scene
longer than a case, a host the bridge firmware is not (another sequence, slot rate or SPI clock), an SPI side
other than ``--spi``, a stimulus too early (or, for ``fluid_leak``, one whose change lasts) for a fault that checks
the resting sensor in the case's first or last frames (``none``, ``fluid_leak``), and, for ``fluid_leak``, whose
prediction is the nominal sensor's, a unit or parameters of the scene's own."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

from bench.campaigns.case_names import CASE_FRAMES, CASE_MAX_S, is_scene_file
from bench.campaigns.faults import LEAK_CASE_FRAMES, REST_MARGIN_FRAMES, REST_MIN_FRAMES
from bench.errors import BenchError, escaped
from emulator.stimuli import AmbientStep, HeaterFailure, PowerOn


class SceneRefused(BenchError, ValueError):
    """A ``--scenes`` scene file the campaign cannot run: one line naming the file and every problem."""


def frame_s() -> float:
    """How long one of the bridge firmware's default frames lasts (s): its slots / the slot rate."""
    from bench.hosts.driver import SLOT_RATE_HZ
    from emulator.channels import DEFAULT_FRAME_NAMES

    return len(DEFAULT_FRAME_NAMES) / SLOT_RATE_HZ


#: stimuli whose change lasts: a step, not a pulse (the sensor is not back at rest after them)
LASTING_CHANGES = (PowerOn, HeaterFailure, AmbientStep)

#: frames a scene-file case streams after the scene's end: the fluid-leak check's last frames, the margin next to a
#: stimulus and one for when START arrives, so that they read the sensor at rest
LEAK_TAIL_FRAMES = LEAK_CASE_FRAMES + REST_MARGIN_FRAMES + 1


def quiet_start_s(fault: str) -> float | None:
    """How late (s from power-on) the first stimulus may come at the earliest for ``fault``'s check of the resting
    sensor in the case's first frames (None: the fault checks none): ``none`` reads REST_MIN_FRAMES frames at rest,
    ``fluid_leak`` LEAK_CASE_FRAMES; each with REST_MARGIN_FRAMES before the stimulus and one frame for START."""
    frames = {"none": REST_MIN_FRAMES + 1, "fluid_leak": LEAK_CASE_FRAMES}.get(fault)
    return None if frames is None else (frames + REST_MARGIN_FRAMES + 1) * frame_s()


@dataclass(frozen=True)
class CampaignScene:
    """A scene file as the campaign runs it: ``label`` names its cases (the file's name, ``grip.toml``: its case
    ``grip.toml[seed=K]``), ``path`` is the file as resolved, ``scene`` the validated scene."""

    label: str
    path: str
    scene: object = field(repr=False)  # bench.scenes.scene.Scene (left out of a failed task's message: its whole text)

    @property
    def stimuli(self) -> list:
        """Sensor 1's stimuli."""
        return list(self.scene.stimuli)

    @property
    def frames(self) -> int:
        """Frames a case reads: the scene's duration and LEAK_TAIL_FRAMES more, at least CASE_FRAMES."""
        return max(CASE_FRAMES, math.ceil(self.scene.duration_s / frame_s() - 1e-9) + LEAK_TAIL_FRAMES)

    def sensors(self, n_sensors: int, seed: int, faults: dict | None = None) -> dict:
        """Sensors 1..``n_sensors`` of the scene with seed ``seed`` (sensor k: seed + k - 1), each with the
        campaign fault's sensor ``faults`` (e.g. a fluid leak)."""
        from bench.hosts.scene_sensors import sensors_from_scene

        scene = self.scene
        if faults:
            scene = dataclasses.replace(scene, faults=dict(faults), common_faults=dict(faults))
        return sensors_from_scene(scene, n_sensors, seed=seed)


def _problems(scene, raw: dict, faults, spi: str) -> list[str]:
    """What of ``scene`` (``raw``: its TOML tables) a campaign of ``faults`` over ``spi`` cannot honour."""
    from bench.errors import SceneError
    from bench.hosts.scene_sensors import firmware_pattern

    problems = []
    if scene.n_sensors > 1:
        problems.append(f"it describes {scene.n_sensors} sensors ([[sensors]] or a stimulus's sensor = "
                        f"{scene.n_sensors}): the campaign's sensor 2 is the faults' own (unplugged, stuck), so a "
                        "scene for it describes sensor 1 only")
    own = {**scene.faults, **(scene.common_faults or {})}
    if own:
        problems.append(f"[faults] / [sensor.faults] {', '.join(sorted(own))}: the campaign injects its own faults "
                        "and checks what each does alone; leave the scene's out")
    if scene.duration_s > CASE_MAX_S:
        problems.append(f"scene.duration_s = {scene.duration_s:g}: a campaign case streams at most {CASE_MAX_S:g} s")
    wanted = raw.get("host", {}).get("spi") if isinstance(raw.get("host"), dict) else None
    if wanted is not None and wanted != spi:
        problems.append(f"host.spi = {wanted!r}: the campaign runs over --spi {spi} (give --spi {wanted}, or leave "
                        "host.spi out)")
    try:
        firmware_pattern(scene)
    except SceneError as e:
        problems += e.problems
    if scene.sequence != "default":
        problems.append("host.sequence: the campaign streams the firmware's default 44-slot frame (its faults are "
                        "timed and checked in it); leave host.sequence out or \"default\"")
    first = min(scene.stimuli, key=lambda st: st.start_s, default=None)
    for fault in faults:
        earliest = quiet_start_s(fault)
        if earliest is not None and first is not None and first.start_s < earliest - 1e-9:
            problems.append(f"its first stimulus ({type(first).__name__} at {first.start_s:g} s) comes before "
                            f"{earliest:g} s: fault {fault} checks the sensor at rest in the case's first frames "
                            f"(start it later, or leave {fault} out of --faults)")
    if "fluid_leak" in faults:
        from emulator.params import SensorParams

        if scene.params != SensorParams():
            problems.append("[sensor] unit / parameters: fault fluid_leak predicts the fall of the resting PDC from "
                            "the nominal sensor's pressure-volume curve (leave fluid_leak out of --faults, or the "
                            "unit and parameters out of the scene)")
        endless = sorted({type(st).__name__ for st in scene.stimuli if isinstance(st, LASTING_CHANGES)})
        if endless:
            problems.append(f"{', '.join(endless)} change the sensor for good: fault fluid_leak compares its resting "
                            "PDC in the case's first and last frames (leave fluid_leak out of --faults)")
    return problems


def campaign_scene(entry: str, faults, spi: str) -> CampaignScene:
    """The ``--scenes`` entry ``entry`` (a scene file, or ``NAME.toml``: a shipped scene when no such file is here)
    as the campaign runs it with ``faults`` (names) over ``spi``; :class:`SceneRefused` in one line naming the file
    and each problem: what the scene loader finds, and what the campaign cannot honour (see the module)."""
    import tomllib

    from bench.cli.scenes import scene_file
    from bench.errors import SceneError
    from bench.scenes.scene import load_scene

    try:
        path = scene_file(entry)
        scene = load_scene(path)
    except SceneError as e:
        raise SceneRefused(f"--scenes {escaped(entry)}: {'; '.join(e.problems)}") from None
    problems = _problems(scene, tomllib.loads(scene.text) if scene.text else {}, list(faults), spi)
    if problems:
        raise SceneRefused(f"--scenes {escaped(entry)}: the campaign cannot run it: {'; '.join(problems)}")
    return CampaignScene(Path(path).name, str(path), scene)


def campaign_scenes(entries, faults, spi: str) -> list:
    """``--scenes``' entries as the campaign runs them: a built-in scene's name as it is, a scene file as a
    :class:`CampaignScene`; :class:`SceneRefused` for the first bad file, or two files whose cases would share a
    name."""
    out = [campaign_scene(e, faults, spi) if is_scene_file(e) else e for e in entries]
    given: dict[str, str] = {}  # a case name -> the entry that gave it
    for entry, s in zip(entries, out):
        if isinstance(s, CampaignScene):
            if s.label in given:
                raise SceneRefused(f"--scenes {escaped(given[s.label])} and {escaped(entry)}: both name their cases "
                                   f"{s.label}[seed=K] (the same file twice, or two files of one name: rename one)")
            given[s.label] = entry
    return out

"""Emulated sensors for the host stacks (bridge firmware, Cheetah adapter) built from a whole scene.

A scene describes one sensor and what happens to it: its parameters, faults, noise switches, fidelity profile,
seed and stimuli.  Behind the bridge or the Cheetah adapter every sensor is built exactly as a scene run builds
its sensor (:func:`bench.running.runner.build_sensor`), reading every channel a host may ask for (its variant's
default frame covers them all: 44 slots, or the BioTac SP's 54 with E20..E24):

* sensor k (1..N) is the scene's sensor k: its unit, parameters and variant (``[sensor]`` for sensor 1,
  ``[[sensors]]`` with ``index = k`` for the others), the stimuli addressed to it (``sensor = k`` on a
  ``[[stimulus]]``; default 1), and seed ``seed + k - 1`` (independent noise);
* sensors the scene does not describe share sensor 1's unit, parameters and variant and feel nothing;
* every sensor has the scene's ``[faults]``, and its own ``[sensor.faults]`` / ``[sensors.faults]`` on top (a
  sensor the scene does not describe has the ``[faults]`` only); every sensor shares the noise switches and
  fidelity;
* each sensor carries its unit's serial number as ``sensor.serial`` (what the host should read as its serial
  property; None for the nominal unit, whose ports keep their default serial, one per sensor number);
* the scene's ``[host]`` section describes the host.  The bridge firmware is the host of the SPI bus: a
  ``sequence`` becomes its sampling pattern; it samples at 4400 slots/s with a 4.4 MHz clock, so other slot
  rates or clocks are refused (they could not be honoured); ``spi`` picks the SPI implementation.  Its pattern
  (1..64 channel indices, each 0..3 or 17..40) holds E20..E24 (36..40) too, but one pattern goes to every
  sensor on the bus: a sequence with E20..E24 needs every sensor to be a BioTac SP (a 19-electrode one would
  answer them with error words only) and is refused otherwise, naming the electrodes and the sensor's variant.
  Behind the Cheetah adapter the host is the user's program, which decides those itself.
"""

from __future__ import annotations

import dataclasses
import numbers

from bench.errors import SceneError
from bench.hosts.cosim import default_sensors
from bench.scenes.limits import MAX_SENSORS
from bench.scenes.scene import with_overrides
from emulator.channels import ALL_CHANNEL_INDEX, HAL, variant
from emulator.sensor import Sensor
from emulator.spi import protocol as proto

FIRMWARE_SLOT_RATE_HZ = 4400.0
FIRMWARE_MAX_PATTERN = 64


def sensors_from_scene(scene, n_sensors: int, seed: int | None = None) -> dict[int, Sensor]:
    """Sensors 1..``n_sensors`` for ``scene`` (see the module docstring); ``seed`` overrides the scene's.
    Refuses (:class:`SceneError`) fewer sensors than the scene describes: their stimuli would be lost."""
    from bench.running.runner import build_sensor

    if n_sensors < scene.n_sensors:
        raise SceneError(scene.source, [f"the scene describes {scene.n_sensors} sensors ([[sensors]] or a stimulus's "
                                        f"sensor = {scene.n_sensors}); serve at least {scene.n_sensors} "
                                        f"(--sensors {scene.n_sensors}), not {n_sensors}"])
    base = scene if seed is None else with_overrides(scene, {"scene.seed": int(seed)})  # (its slides redrawn too)
    out = {}
    for k in range(1, n_sensors + 1):
        one = dataclasses.replace(base.for_sensor(k), sequence="default")
        out[k] = build_sensor(one)
    return out


def firmware_pattern(scene) -> list[int] | None:
    """The bridge firmware's sampling pattern for the scene's ``host.sequence`` (None: the default frame).
    Refuses, naming the field, what the firmware cannot do: other slot rates or SPI clocks, long patterns, and
    E20..E24 unless every sensor of the scene is a BioTac SP (sensors the scene does not describe are sensor 1's
    twins, so its sensors 1..N speak for any number served)."""
    problems = []
    if abs(scene.slot_rate_Hz - FIRMWARE_SLOT_RATE_HZ) > 1e-9:
        problems.append(f"host.slot_rate_Hz = {scene.slot_rate_Hz:g}: the bridge firmware samples at "
                        f"{FIRMWARE_SLOT_RATE_HZ:g} slots/s (run the scene with 'biotac-bench run' instead)")
    if abs(scene.spi_clock_Hz - proto.HOST_DEFAULT_CLOCK_HZ) > 1e-6:
        problems.append(f"host.spi_clock_Hz = {scene.spi_clock_Hz:g}: the bridge firmware clocks SPI at "
                        f"{proto.HOST_DEFAULT_CLOCK_HZ:g} Hz")
    pattern = None
    if scene.sequence != "default":
        names = list(scene.sequence)
        pattern = [ALL_CHANNEL_INDEX[n] for n in names if n in ALL_CHANNEL_INDEX]
        bad = [n for n in names if ALL_CHANNEL_INDEX.get(n, HAL) == HAL]
        if bad:
            problems.append(f"host.sequence: {', '.join(map(str, bad))}: the firmware samples PAC, PDC, TAC, TDC, "
                            "E1..E24 (E20..E24 from a \"biotac-sp\")")
        problems += _electrodes_missing(scene, names)
        if not 1 <= len(names) <= FIRMWARE_MAX_PATTERN:
            problems.append(f"host.sequence has {len(names)} slots: the bridge firmware's pattern holds 1 to "
                            f"{FIRMWARE_MAX_PATTERN}")
    if problems:
        raise SceneError(scene.source, problems)
    return pattern


def _electrodes_missing(scene, names: list) -> list[str]:
    """A problem per sensor variant of the scene that lacks some of the electrodes ``names`` asks for."""
    short: dict[str, tuple[list, list]] = {}  # variant -> (its sensors, the electrodes it lacks)
    for k in range(1, scene.n_sensors + 1):
        v = variant(scene.sensor_spec(k).variant)
        missing = [n for n in dict.fromkeys(names) if n in ALL_CHANNEL_INDEX and n not in v.channel_index]
        if missing:
            short.setdefault(v.name, ([], missing))[0].append(k)
    out = []
    for name, (sensors, missing) in short.items():
        who = (f"sensor {sensors[0]} is a" if len(sensors) == 1 else
               f"sensors {', '.join(map(str, sensors))} are each a")
        out.append(f"host.sequence: {', '.join(missing)}: {who} {name!r}, with E1..E{variant(name).n_electrodes} "
                   "only; the bridge firmware sends one pattern to every sensor, so it "
                   "samples E20..E24 only when every sensor is a \"biotac-sp\" (a 19-electrode sensor would "
                   "answer them with error words, never data; 'biotac-bench run' reads them from the SPs of a mixed "
                   "scene)")
    return out


def _whole_1_to_max(n) -> bool:
    return isinstance(n, numbers.Integral) and not isinstance(n, bool) and 1 <= n <= MAX_SENSORS


def bench_sensors(n_sensors, sensors, stimuli, seed: int, variant: str) -> dict:
    """The emulated sensors a host bench serves: ``sensors`` (sensor number -> Sensor) if given, else ``n_sensors``
    default ones (:func:`bench.hosts.cosim.default_sensors`).  A count or numbers outside 1..MAX_SENSORS (what the
    bridge firmware and the Cheetah adapter address) are refused with a ValueError naming them."""
    if sensors is not None:
        if not sensors:
            raise ValueError("sensors = {}: no sensors on the bus; give {number: Sensor} for 1 to "
                             f"{MAX_SENSORS} sensors, or leave sensors out for n_sensors default ones")
        bad = [n for n in sensors if not _whole_1_to_max(n)]
        if bad:
            raise ValueError(f"sensors numbered {bad!r}: sensor numbers are 1 to {MAX_SENSORS}")
        # a Sensor, or a wrapper that samples like one (a test's recording proxy): the bus calls .sample
        odd = {n: s for n, s in sensors.items() if not (isinstance(s, Sensor) or callable(getattr(s, "sample", None)))}
        if odd:
            raise ValueError(f"sensors = {odd!r}: each must be an emulator.sensor.Sensor (or sample like one)")
        first: dict[int, int] = {}  # id of a sensor object -> the first number it was given
        for n, s in sensors.items():
            if id(s) in first:  # one object answering two numbers: each asks it for instants the other has passed
                raise ValueError(f"sensors {first[id(s)]} and {n} are the same Sensor object: each sensor number needs "
                                 f"a sensor of its own (build one per number)")
            first[id(s)] = n
        return dict(sensors)
    if not _whole_1_to_max(n_sensors):
        raise ValueError(f"n_sensors = {n_sensors!r}: must be a whole number from 1 to {MAX_SENSORS} "
                         f"(sensors on the bus)")
    return default_sensors(int(n_sensors), stimuli, seed, variant)

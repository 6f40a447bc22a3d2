"""Several fingers in one scene (issue 10.7): stimuli reach the sensor they name, each sensor is its own unit, and
every host path — ``run``, the bridge firmware read by the driver's parser, the Cheetah adapter — sees each
finger's own signals: a finger's PDC rises at its own touch and only then, whatever the other fingers do."""

from __future__ import annotations

import ctypes as C

import numpy as np
import pytest

from bench.paths import FIXTURES
from bench.scenes.scene import load_scene, parse_scene_text
from bench.tests.host_benches import cheetah_adapter, run_firmware
from emulator.channels import channel_index
from emulator.spi import protocol as proto
from emulator.units import serial_for, unit

GRASP = FIXTURES / "scenes" / "grasp_three_fingers.toml"
#: when each finger meets the object (s): the touches' and the slide's starts in grasp_three_fingers.toml
ONSET_S = {1: 0.5, 2: 0.9, 3: 1.2}
SETTLED_S = 0.3  # after its onset a finger's force has ramped up (touch ramp 0.25 s, slide approach 0.1 s)
QUIET_CODES = 6.0  # largest departure from rest before a finger's own touch (PDC noise is ~1 code)
RISE_CODES = 40.0  # smallest rise once pressed (0.8 N at 11.5 mN/bit is ~70 codes)


def check_own_touch_only(times: dict, pdc: dict) -> dict:
    """Per sensor: PDC at rest until its own onset (while the others press), risen after; returns the rises."""
    rises = {}
    for k, onset in ONSET_S.items():
        t, code = np.asarray(times[k]), np.asarray(pdc[k], float)
        rest = code[(t > 0.05) & (t < 0.45)].mean()
        before = code[(t > 0.05) & (t < onset - 0.02)]
        assert np.abs(before - rest).max() < QUIET_CODES, (k, np.abs(before - rest).max())
        pressed = code[(t > onset + SETTLED_S) & (t < onset + SETTLED_S + 0.2)]
        rises[k] = pressed.mean() - rest
        assert rises[k] > RISE_CODES, (k, rises[k])
    return rises


def test_the_grasp_scene_gives_each_finger_its_unit_and_its_stimuli():
    sc = load_scene(GRASP)
    assert sc.n_sensors == 3 and sc.serial == serial_for(17) and sc.params == unit(17).params
    assert sc.sensors[2].params == unit(18).params and sc.sensors[3].unit == "nominal"
    assert [len(sc.sensor_spec(k).stimuli) for k in (1, 2, 3)] == [1, 1, 1]
    assert sc.for_sensor(3).stimuli[0].start_s == ONSET_S[3] and sc.for_sensor(3).seed == sc.seed + 2


def test_the_grasp_scene_is_the_hand_the_readme_describes():
    """README: thumb (unit 17) at 0.5 s with 2 N, index (unit 18) at 0.9 s with 1.2 N, the middle finger lands at
    1.3 s (0.8 N) and slips 8 mm."""
    sc = load_scene(GRASP)
    thumb, index, middle = (sc.for_sensor(k).stimuli[0] for k in (1, 2, 3))
    assert (thumb.start_s, thumb.force_N) == (0.5, 2.0) and (index.start_s, index.force_N) == (0.9, 1.2)
    assert middle.start_s + middle.approach_s == pytest.approx(1.3) and middle.force_N == 0.8
    assert middle.distance_m == pytest.approx(0.008)


def test_stimuli_of_sensor_2_do_not_reach_sensor_1():
    sc = parse_scene_text('[scene]\nname = "s"\nduration_s = 1.0\n[[stimulus]]\nkind = "tap"\nat_s = 0.5\n'
                          'peak_N = 1.0\nsensor = 2\n')
    assert sc.stimuli == [] and len(sc.sensors[2].stimuli) == 1 and sc.n_sensors == 2
    assert sc.sensors[2].params == sc.params and sc.sensors[2].serial == ""  # not declared: sensor 1's twin


def test_run_records_every_finger_and_each_rises_at_its_own_touch():
    from bench.running.runner import run_scene

    rec = run_scene(load_scene(GRASP), progress=False)
    assert rec.status == "ok", rec.error
    recs = {1: rec, **rec.sensors}
    assert sorted(recs) == [1, 2, 3] and recs[3].scene.name == "grasp-three-fingers-sensor3"
    times = {k: r.channels["PDC"].times for k, r in recs.items()}
    rises = check_own_touch_only(times, {k: r.channels["PDC"].codes for k, r in recs.items()})
    assert rises[1] > rises[2] > rises[3]  # 2.0 N, 1.2 N, 0.8 N
    # README: each finger's own force, read through the published 11.5 mN per PDC bit (each unit's own scale and the
    # skin's creep within 10 %)
    assert [r * 0.0115 for r in rises.values()] == pytest.approx([2.0, 1.2, 0.8], rel=0.10), rises
    assert len(recs[3].slides) == 1 and not recs[1].slides  # the slip is the middle finger's
    assert recs[3].slides[0]["distance_m"] == pytest.approx(0.008)  # "slips 8 mm over acrylic"
    rest = [r.channels["PDC"].codes[:20].mean() for r in recs.values()]
    assert np.ptp(rest) > 10  # three units: three resting levels


@pytest.mark.firmware
def test_the_bridge_firmware_and_driver_see_each_fingers_own_touch():
    from bench.hosts.scene_sensors import firmware_pattern, sensors_from_scene

    sc = load_scene(GRASP)
    sc.sequence = ["PDC", "TDC"]  # two slots: PDC at 2.2 kHz for all three sensors
    run = run_firmware(sensors_from_scene(sc, 3), 1.8, pattern=firmware_pattern(sc), status=False)
    frames = run.frames
    assert frames and frames[-1].sensors == [1, 2, 3]
    slot_s = 1.0 / 4400.0
    t0 = run.t_end - len(frames) * 2 * slot_s  # frames are back to back from the start command on
    times, pdc = {}, {}
    for k in (1, 2, 3):
        codes = [f.samples(k)["PDC"] for f in frames]
        times[k] = t0 + np.arange(len(frames)) * 2 * slot_s
        pdc[k] = np.array([c[0] if c.size else np.nan for c in codes])
    check_own_touch_only(times, pdc)


def _pdc_through_cheetah(lib, h, n_samples: int, period_s: float) -> np.ndarray:
    """PDC of sensors 1..3 through the Cheetah API the way the vendor's host code reads: command to all,
    50 µs, each sensor read in turn; one sample every ``period_s``; returns codes[sample, sensor]."""
    select = (0x01, 0x02, 0x04)
    cmd = int(proto.sample_command(channel_index("PDC")))
    per = 2 + 2 * len(select)
    lib.c_ch_spi_queue_clear(h)
    for _ in range(n_samples):
        lib.c_ch_spi_queue_ss(h, 0x07)
        lib.c_ch_spi_queue_byte(h, 1, cmd)
        lib.c_ch_spi_queue_byte(h, 1, 0x00)
        lib.c_ch_spi_queue_ss(h, 0)
        lib.c_ch_spi_queue_delay_ns(h, 50000)
        for s in select:
            lib.c_ch_spi_queue_ss(h, s)
            lib.c_ch_spi_queue_byte(h, 2, 0x00)
        lib.c_ch_spi_queue_ss(h, 0)
        lib.c_ch_spi_queue_delay_ns(h, int(period_s * 1e9) - 60000)
    buf = (C.c_uint8 * (per * n_samples))()
    assert lib.c_ch_spi_batch_shift(h, per * n_samples, buf) == per * n_samples
    data = np.frombuffer(bytes(buf), np.uint8).reshape(n_samples, per)
    words = (data[:, 2::2].astype(np.uint16) << 8) | data[:, 3::2]
    value, ok = proto.decode_response(words)
    assert ok.all()
    return value


@pytest.mark.firmware
def test_the_cheetah_adapter_serves_each_fingers_own_touch(monkeypatch):
    from bench.hosts.scene_sensors import sensors_from_scene

    sc = load_scene(GRASP)
    with cheetah_adapter(monkeypatch, 3, sensors=sensors_from_scene(sc, 3)) as (cb, lib, h):
        t_start = cb.t
        period = 0.005
        parts = [_pdc_through_cheetah(lib, h, 60, period) for _ in range(6)]  # 1.8 s in batches of 0.3 s
    codes = np.concatenate(parts)
    t = t_start + np.arange(len(codes)) * period
    check_own_touch_only({k: t for k in (1, 2, 3)}, {k: codes[:, k - 1] for k in (1, 2, 3)})


def test_the_run_command_writes_each_fingers_own_report(tmp_path):
    import json

    from bench.tests.cli_runs import run_cli

    out = tmp_path / "grasp"
    r = run_cli("run", GRASP, "--out", out, "--quiet", "--no-plots", timeout=300)
    assert r.returncode == 0, r.stderr
    assert "for sensor 2 (unit 18, serial BTU0000000000018" in r.stdout
    for k, folder in ((1, out), (2, out / "sensor2"), (3, out / "sensor3")):
        record = json.loads((folder / "record.json").read_text())
        assert record["status"] == "ok" and (folder / "report.md").is_file() and (folder / "codes.npz").is_file()
        pdc = np.load(folder / "codes.npz")["PDC_code"]
        assert pdc.max() - pdc[:20].mean() > RISE_CODES, k  # each folder holds its own finger's touch


def test_a_finger_can_be_a_biotac_sp_and_its_own_e22_feels_its_touch():
    from bench.hosts.scene_sensors import sensors_from_scene

    sc = parse_scene_text('[scene]\nname = "sp"\nduration_s = 1.0\n[[sensors]]\nindex = 2\nvariant = "biotac-sp"\n'
                          'unit = 5\n[[stimulus]]\nkind = "touch"\nsensor = 2\nelectrode = "E22"\nstart_s = 0.2\n'
                          'ramp_s = 0.05\nhold_s = 0.7\n'  # ends at 1.0 s, with the scene
                          'force_N = 1.0\n[noise]\nadc = false\nspi_coupling = false\n')
    sensors = sensors_from_scene(sc, 2)
    assert [s.variant.name for s in sensors.values()] == ["biotac", "biotac-sp"]
    assert sensors[2].params == unit(5).params and "E22" in sc.for_sensor(2).channels
    e22 = sensors[2].variant.channel_index["E22"]
    rest, pressed = sensors[2].sample(np.array([e22, e22]), np.array([0.1, 0.9]))
    assert abs(int(pressed) - int(rest)) > 50  # the SP finger's own fifth-row electrode moves
    e17 = channel_index("E17")
    a, b = sensors[1].sample(np.array([e17, e17]), np.array([0.1, 0.9]))
    assert abs(int(a) - int(b)) <= 3  # sensor 1 feels nothing



ONE_SLIDE = """
[scene]
name = "slide"
duration_s = 3.0
seed = {seed}
{sensors}
[[stimulus]]
kind = "slide"
start_s = 0.3
texture = "60-grit sandpaper"
force_N = 0.5
velocity_mm_per_s = 10
distance_mm = 10
sensor = {sensor}
"""


def _slide_start_m(seed: int, sensor: int) -> float:
    """Where the one slide of a scene of ``seed`` starts on its texture, slid by finger ``sensor`` (1 or 2)."""
    scene = parse_scene_text(ONE_SLIDE.format(seed=seed, sensor=sensor,
                                              sensors="[[sensors]]\nindex = 2\n" if sensor == 2 else ""), "s.toml")
    (slide,) = [s for s in scene.sensor_spec(sensor).stimuli if hasattr(s, "start_position_m")]
    return slide.start_position_m


def test_each_finger_draws_its_slides_start_positions_from_its_own_seed():
    """Sensor k draws from seed + k − 1 (README): finger 2's slide starts where a one-finger scene of seed 8 starts,
    not where finger 1's of seed 7 does — two fingers never slide over the same spot by accident."""
    assert _slide_start_m(7, sensor=2) == _slide_start_m(8, sensor=1) != _slide_start_m(7, sensor=1)


DROPS_ON_FINGER_2 = """
[scene]
name = "drops-on-finger-2"
duration_s = 2.0
seed = 3
[analysis]
impact_detection = true
[[sensors]]
index = 2
[[stimulus]]
kind = "sphere_drop"
sphere = "1 mm aluminum bearing"
at_s = [0.5, 1.0]
sensor = 2
"""


def test_impact_detection_judges_the_drops_of_every_finger(tmp_path):
    """Drops only on finger 2 (the scene was refused: "no sphere_drop to judge"): finger 2's record and report carry
    D's rule applied to its two drops of a 1 mm aluminum bearing from 7 cm — detected, as D Table 5-2 has it —
    and finger 1, with nothing dropped on it, carries no detection table."""
    import json

    from bench.cli import main as cli

    scene = tmp_path / "drops.toml"
    scene.write_text(DROPS_ON_FINGER_2)
    out = tmp_path / "o"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet", "--no-plots"]) == 0
    first, second = (json.loads((out / sub / "record.json").read_text()) for sub in (".", "sensor2"))
    assert "impact_detection" not in first
    assert second["impact_detection"]["spheres"]["1 mm aluminum bearing"] | {"energy_uJ": None} == {
        "mass_mg": pytest.approx(1.461, abs=1e-3), "energy_uJ": None, "drops": 2, "detected": 2, "detection_rate": 1.0}
    assert "## Impact detection" in (out / "sensor2" / "report.md").read_text()


@pytest.mark.unit
def test_a_finger_that_stops_stops_the_run_and_the_record_says_which():
    """Three fingers, a stop asked for while finger 2 runs (after finger 1's chunk boundaries): the run's status is
    finger 2's ("interrupted"), and finger 3 never runs; asked while finger 1 runs, no other finger runs."""
    from bench.running.runner import run_scene

    scene = parse_scene_text('[scene]\nname = "three"\nduration_s = 3.0\n[[sensors]]\nindex = 2\n'
                             '[[sensors]]\nindex = 3\n')
    assert scene.n_sensors == 3
    asked = []
    whole = run_scene(scene, progress=False, should_stop=lambda: bool(asked.append(1)))
    assert whole.status == "ok" and sorted(whole.sensors) == [2, 3]
    per_finger = len(asked) // 3  # each finger asks at each of its chunk boundaries

    def stop_after(n):
        calls = []
        return lambda: bool(calls.append(1)) or len(calls) > n

    during_2 = run_scene(scene, progress=False, should_stop=stop_after(per_finger))
    assert during_2.status == "interrupted" and during_2.sensors[2].status == "interrupted"
    assert sorted(during_2.sensors) == [2]
    during_1 = run_scene(scene, progress=False, should_stop=stop_after(0))
    assert during_1.status == "interrupted" and during_1.sensors == {}


@pytest.mark.unit
def test_a_stop_asked_after_the_last_chunk_leaves_the_run_complete():
    """A stop that arrives once every sample is taken (here: asked at every chunk boundary of a one-chunk run)
    changes nothing: the run is "ok" with all its seconds, not "interrupted"."""
    from bench.running.runner import run_scene

    scene = parse_scene_text('[scene]\nname = "one-chunk"\nduration_s = 1.0\n')
    rec = run_scene(scene, progress=False, chunk_s=1.0, should_stop=lambda: True)
    assert rec.status == "ok" and rec.simulated_s == pytest.approx(1.0)


def test_a_failed_fingers_error_names_the_finger(monkeypatch):
    """Finger 2 of three fails: the run fails with finger 2's error prefixed "sensor 2: " (run_scene's contract: the
    recording is finger 1's, so its error must say which finger failed), and finger 3 never runs."""
    from bench.running import runner

    real, calls = runner.run_one_sensor, []

    def second_fails(scene, *args, **kw):
        rec = real(scene, *args, **kw)
        calls.append(scene)
        if len(calls) == 2:
            rec.error, rec.status = "RuntimeError: the bus fell off", "failed"
        return rec

    monkeypatch.setattr(runner, "run_one_sensor", second_fails)
    scene = parse_scene_text('[scene]\nname = "three"\nduration_s = 0.3\n[[sensors]]\nindex = 2\n'
                             '[[sensors]]\nindex = 3\n')
    rec = runner.run_scene(scene, progress=False)
    assert rec.status == "failed" and rec.error == "sensor 2: RuntimeError: the bus fell off"
    assert len(calls) == 2


def test_a_stopped_run_records_the_time_it_reached_not_the_scenes():
    """A stop asked at the first chunk boundary (chunks of 1 simulated s, run_scene's default) of a 3 s scene: the
    recording's simulated_s is the 1.0 s reached (to one slot, 1/4400 s), status "interrupted"."""
    from bench.running.runner import run_scene

    scene = parse_scene_text('[scene]\nname = "short"\nduration_s = 3.0\n')
    rec = run_scene(scene, progress=False, should_stop=lambda: True)
    assert rec.status == "interrupted"
    assert rec.simulated_s == pytest.approx(1.0, abs=1 / scene.slot_rate_Hz)

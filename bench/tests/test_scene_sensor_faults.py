"""Faults per finger: a scene's [faults] reach every sensor; a sensor's own ``[sensor.faults]`` (sensor 1) or
``[sensors.faults]`` (after its ``[[sensors]]`` table) reach that sensor only — so a hand can have one finger with a
broken thermistor or an open electrode while the others are healthy, and the host (``run``, the bridge firmware read
by the driver's parser) sees the fault on that finger alone.  A fault given both scene-wide and in a sensor's own
table is refused (which one holds would be a guess), as is an electrode open in one and shorted in the other; a
sensor's own electrode numbers run 1..its own variant's electrodes."""

from __future__ import annotations

import numpy as np
import pytest

from bench.errors import SceneError
from bench.scenes.scene import parse_scene_text
from emulator.channels import channel_index

HAND = """
[scene]
name = "hand"
duration_s = 0.5
[noise]
adc = false
spi_coupling = false
[faults]
electrode_open = [3]
[sensor.faults]
mux_stuck = 3
[[sensors]]
index = 2
[sensors.faults]
thermistor = "open"
[[stimulus]]
kind = "tap"
sensor = 3
at_s = 0.2
peak_N = 0.5
"""


def _codes(sensor, names, at_s=0.3):
    """One code per channel name at ``at_s``."""
    idx = np.array([channel_index(n) for n in names])
    return dict(zip(names, sensor.sample(idx, np.full(idx.size, at_s)).astype(int)))


@pytest.mark.unit
def test_each_sensor_has_the_scenes_faults_and_its_own():
    sc = parse_scene_text(HAND, "hand.toml")
    assert sc.faults == {"electrode_open": [3], "mux_stuck": 3}  # sensor 1's: [faults] and [sensor.faults]
    assert sc.common_faults == {"electrode_open": [3]}
    assert sc.sensor_spec(2).faults == {"electrode_open": [3], "thermistor": "open"}
    assert sc.sensor_spec(3).faults == {"electrode_open": [3]}  # addressed by a stimulus only: the common faults
    assert [sc.for_sensor(k).faults for k in (1, 2, 3)] == [sc.sensor_spec(k).faults for k in (1, 2, 3)]


@pytest.mark.unit
def test_the_sensors_built_for_a_host_carry_each_fingers_own_faults():
    """What the bridge firmware, the Cheetah adapter and ``run`` serve: sensor 2 alone reads TDC 0 (open thermistor);
    E3 is open on every finger ([faults]), and sensor 1's multiplexer is stuck on it, so every electrode channel of
    sensor 1 alone reads near the bottom rail."""
    from bench.hosts.scene_sensors import sensors_from_scene

    sensors = sensors_from_scene(parse_scene_text(HAND, "hand.toml"), 3)
    codes = {k: _codes(s, ["TDC", "E3", "E12", "E19"]) for k, s in sensors.items()}
    assert codes[2]["TDC"] == 0 and codes[1]["TDC"] > 100 and codes[3]["TDC"] > 100
    assert all(c["E3"] < 100 for c in codes.values())
    assert codes[1]["E12"] < 100 and codes[1]["E19"] < 100
    assert all(codes[k][e] > 2000 for k in (2, 3) for e in ("E12", "E19"))


@pytest.mark.unit
def test_a_biotac_sp_finger_faults_its_own_e20_to_e24_in_a_mixed_hand():
    from bench.hosts.scene_sensors import sensors_from_scene

    sc = parse_scene_text('[scene]\nname = "mixed"\nduration_s = 0.5\n[noise]\nadc = false\n[sensor]\n'
                          'variant = "biotac-sp"\n[sensor.faults]\nelectrode_open = [22]\n[[sensors]]\nindex = 2\n'
                          'variant = "biotac-sp"\n[[sensors]]\nindex = 3\n', "mixed.toml")
    assert sc.faults == {"electrode_open": [22]} and sc.sensor_spec(2).faults == {}
    sensors = sensors_from_scene(sc, 3)
    e22 = {k: int(sensors[k].sample([sensors[k].variant.channel_index["E22"]] * 2, [0.3, 0.3002])[-1]) for k in (1, 2)}
    assert e22[1] < 100 and e22[2] > 2000, e22  # the faulted SP finger's E22 only


@pytest.mark.unit
def test_one_fingers_leak_empties_that_finger_only():
    from bench.hosts.scene_sensors import sensors_from_scene

    sc = parse_scene_text('[scene]\nname = "leak"\nduration_s = 10.0\n[noise]\nadc = false\n[[sensors]]\nindex = 3\n'
                          '[sensors.faults]\nfluid_leak_mL_per_min = 6.0\n', "leak.toml")
    sensors = sensors_from_scene(sc, 3)
    pdc = {k: s.sample([channel_index("PDC")] * 2, [0.05, 5.0]).astype(int) for k, s in sensors.items()}
    assert pdc[1][1] == pdc[1][0] and pdc[2][1] == pdc[2][0], pdc  # the healthy fingers keep their pressure
    assert pdc[3][0] - pdc[3][1] > 100, pdc  # a punctured finger: empty after 5 s


@pytest.mark.unit
def test_a_sensor_served_beyond_the_scenes_has_the_common_faults_and_rests():
    """``bridge --sensors 4`` on a three-finger scene: sensor 4 is sensor 1's unit with the scene's [faults] only
    (E3 open; its multiplexer, sensor 1's own fault, not stuck), feeling nothing."""
    from bench.hosts.scene_sensors import sensors_from_scene

    fourth = sensors_from_scene(parse_scene_text(HAND, "hand.toml"), 4)[4]
    pdc = fourth.sample([channel_index("PDC")] * 3, [0.05, 0.2, 0.25]).astype(int)
    assert np.ptp(pdc) <= 1, pdc  # no stimulus reaches it (sensor 3's tap at 0.2 s is sensor 3's)
    codes = _codes(fourth, ["TDC", "E3", "E12"])
    assert codes["E3"] < 100 and codes["E12"] > 2000 and codes["TDC"] > 100


@pytest.mark.unit
@pytest.mark.parametrize("text, words", [
    # a 19-electrode finger's own table: 1..19, and says why
    ('[[sensors]]\nindex = 2\n[sensors.faults]\nelectrode_open = [22]\n',
     'sensors[0].faults.electrode_open = [22]: a list of electrode numbers 1..19 (this sensor is a "biotac")'),
    ('[sensor]\nvariant = "biotac-sp"\n[sensor.faults]\nmux_stuck = 25\n',
     "sensor.faults.mux_stuck = 25: allowed range is 1 to 24"),
    ('[sensor]\nvariant = "biotac-sp"\n[[sensors]]\nindex = 2\n[faults]\nmux_stuck = 22\n',  # a mixed hand
     "faults.mux_stuck = 22: allowed range is 1 to 19 electrode number (every sensor of the scene has the [faults]; "
     "a \"biotac-sp\"'s E20..E24 go in its own [sensor.faults] or [sensors.faults])"),
    # one fault in two places
    ('[faults]\nthermistor = "short"\n[sensor.faults]\nthermistor = "open"\n',
     'sensor.faults.thermistor: [faults] already gives thermistor = "short" to every sensor'),
    ('[faults]\nheater_failed = true\n[sensor.faults]\nheater_failed = false\n',  # "false" is a statement too
     'sensor.faults.heater_failed: [faults] already gives heater_failed = true to every sensor'),
    ('[faults]\nfluid_leak_mL_per_min = 5.0\n[sensor.faults]\nfluid_leak_start_s = 0.1\n',
     "sensor.faults.fluid_leak_start_s = 0.1: a leak needs its rate too, in the same table"),
    # open in one, shorted in the other
    ('[faults]\nelectrode_open = [4]\n[[sensors]]\nindex = 2\n[sensors.faults]\nelectrode_short = [4, 5]\n',
     "sensors[0].faults: electrode 4 is both open (faults.electrode_open = [4]) and shorted "
     "(sensors[0].faults.electrode_short = [4, 5])"),
    ('[[sensors]]\nindex = 2\n[sensors.faults]\nelectrode_open = [6]\nelectrode_short = [6]\n',
     "sensors[0].faults: electrode 6 is both open (sensors[0].faults.electrode_open = [6])"),
    # a dead heater cannot fail; on its own finger only
    ('[[sensors]]\nindex = 2\n[sensors.faults]\nheater_failed = true\n'
     '[[stimulus]]\nkind = "heater_failure"\nsensor = 2\nat_s = 0.1\n',
     "heater_failure at 0.1 s (sensor 2): sensors[0].faults.heater_failed = true says the heaters never ran"),
    # shapes and names
    ('[sensor]\nfaults = 3\n', "sensor.faults = 3: must be a table ([sensor.faults] after the sensor's table)"),
    ('[sensor.faults]\nelectrode_broken = [1]\n', 'sensor.faults: unknown field "electrode_broken"'),
    ('[sensor.faults]\nfluid_leak_start_s = 0.1\n', "sensor.faults.fluid_leak_start_s = 0.1: a leak needs its rate"),
])
def test_a_sensors_own_faults_are_checked_by_name(text, words):
    with pytest.raises(SceneError) as e:
        parse_scene_text('[scene]\nname = "f"\nduration_s = 0.5\n' + text, "f.toml")
    assert words in str(e.value)


@pytest.mark.unit
def test_a_dead_heater_on_one_finger_leaves_the_others_heater_failure_alone():
    sc = parse_scene_text('[scene]\nname = "f"\nduration_s = 0.5\n[[sensors]]\nindex = 2\n[sensors.faults]\n'
                          'heater_failed = true\n[[stimulus]]\nkind = "heater_failure"\nat_s = 0.1\n', "f.toml")
    assert sc.sensor_spec(2).faults == {"heater_failed": True} and "heater_failed" not in sc.faults


@pytest.mark.unit
def test_the_sensors_of_a_scene_do_not_share_one_faults_table():
    sc = parse_scene_text(HAND, "hand.toml")
    sc.sensor_spec(3).faults["thermistor"] = "short"  # a caller changing one finger's faults in memory
    assert sc.common_faults == {"electrode_open": [3]} and sc.sensor_spec(4).faults == {"electrode_open": [3]}


@pytest.mark.firmware
def test_the_bridge_command_names_every_served_fingers_faults(tmp_path, capsys):
    from bench.cli import main as cli

    scene = tmp_path / "hand.toml"
    scene.write_text(HAND)
    assert cli.main(["bridge", "--scene", str(scene), "--sensors", "4", "--fast", "--seconds", "0.1"]) == 0
    out = capsys.readouterr().out
    assert ("faults — sensor 1: electrode_open=[3], mux_stuck=3; sensor 2: electrode_open=[3], thermistor=open; "
            "sensor 3: electrode_open=[3]; sensor 4: electrode_open=[3])") in out, out


@pytest.mark.firmware
def test_the_bridge_firmware_and_driver_see_the_fault_on_its_finger_only():
    from bench.hosts.scene_sensors import sensors_from_scene
    from bench.tests.host_benches import run_firmware

    sc = parse_scene_text(HAND, "hand.toml")
    run = run_firmware(sensors_from_scene(sc, 3), 0.2, status=False)
    assert run.frames and run.frames[-1].sensors == [1, 2, 3]
    tdc = {k: np.concatenate([f.samples(k)["TDC"] for f in run.frames]) for k in (1, 2, 3)}
    assert (tdc[2] == 0).all() and (tdc[1] > 100).all() and (tdc[3] > 100).all()


def test_the_run_command_records_each_fingers_faults(tmp_path):
    import json

    from bench.tests.cli_runs import run_cli

    scene = tmp_path / "hand.toml"
    scene.write_text(HAND)
    out = tmp_path / "out"
    r = run_cli("run", scene, "--out", out, "--quiet", "--no-plots", timeout=300)
    assert r.returncode == 0, r.stderr
    for k, folder in ((1, out), (2, out / "sensor2"), (3, out / "sensor3")):
        record = json.loads((folder / "record.json").read_text())
        assert record["faults"] == parse_scene_text(HAND).sensor_spec(k).faults, k
        tdc = np.load(folder / "codes.npz")["TDC_code"]
        assert (tdc == 0).all() == (k == 2), k
        assert "- faults: `electrode_open = [3]`" in (folder / "report.md").read_text()
    assert "for sensor 2 (unit nominal, serial BT" in r.stdout and "electrode_open = [3], thermistor = open)" in r.stdout


@pytest.mark.firmware
def test_cheetah_serve_with_the_scene_serves_each_fingers_faults(tmp_path, monkeypatch):
    """``biotac-bench cheetah serve SCENE`` as a user starts it: a vendor-style program reads TDC 0 from finger 2
    (its own open thermistor) only."""
    import ctypes as C
    import subprocess
    import sys

    from bench.hosts.cheetah_server import build_library
    from bench.paths import REPO
    from bench.tests.host_benches import read_sample

    scene = tmp_path / "hand.toml"
    scene.write_text(HAND)
    p = subprocess.Popen([sys.executable, "-m", "bench.cli", "cheetah", "serve", str(scene), "--seconds", "60"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO)
    try:
        line = p.stdout.readline()
        assert line.startswith("export BIOTAC_CHEETAH_SOCKET="), (line, p.stderr.read() if p.poll() else "")
        monkeypatch.setenv("BIOTAC_CHEETAH_SOCKET", line.split("=", 1)[1].strip().strip("'"))
        lib = C.CDLL(str(build_library()))
        h = lib.c_ch_open(0)
        assert h == 1
        lib.c_ch_spi_bitrate(h, 4400)
        tdc = {k: read_sample(lib, h, "TDC", select=1 << (k - 1)) for k in (1, 2, 3)}  # selects 0x01, 0x02, 0x04
        lib.c_ch_close(h)
    finally:
        p.terminate()
        p.wait(timeout=30)
    assert tdc[2] == 0 and tdc[1] > 100 and tdc[3] > 100, tdc

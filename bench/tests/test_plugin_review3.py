"""The pytest plugin as its docstring and the README promise it (review 3): the variant reaches the sensors the
factories build (units or not, bridge and Cheetah alike), ``scene=`` on every factory that builds a sensor, a
bridge or a Cheetah bench, a BioTac SP sensor answers its whole frame, and misuse fails the user's test with one
clear message (no traceback into the plugin)."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from bench.hosts.driver import BridgeDriver
from bench.tests.test_cli_review3 import sp_scene as write_sp_scene
from emulator.spi import protocol as proto
from emulator.spi.model import PROP_SERIAL
from emulator.spi.peripheral import TransferBatch

pytestmark = pytest.mark.firmware
pytest_plugins = ["pytester"]

@pytest.fixture
def sp_scene(tmp_path):
    """A scene file of two BioTac SPs, units 17 and 18."""
    return write_sp_scene(tmp_path)


def first_frame(port: str):
    """One data frame from the bridge at ``port`` (after START)."""
    driver = BridgeDriver(port)
    try:
        driver.start()
        return next(driver.frames(max_frames=1))
    finally:
        driver.close()


def read_channel(spi, channel: int, n: int = 3, t0: float = 0.05):
    """``n`` samples of ``channel`` (index) read from a sensor's SPI side: (values, parity ok, raw answers)."""
    start, mosi = [], []
    for k in range(n):
        t = t0 + k * 250e-6
        start += [t, t + 60e-6]
        mosi += [int(proto.sample_command(channel)) << 8, 0]
    miso = spi.exchange(TransferBatch(np.array(start), np.array(mosi, np.uint16)))
    values, ok = proto.decode_response(miso[1::2])
    return values, ok, miso[1::2]


# --- 1. the variant reaches the sensors built from units ----------------------------------------------------------


def test_units_with_the_sp_variant_stream_the_54_slot_frame(biotac_bridge):
    bench = biotac_bridge(2, units=[17, 18], variant="biotac-sp")
    assert [bench.board.sensors[k].variant.name for k in (1, 2)] == ["biotac-sp", "biotac-sp"]
    assert first_frame(bench.port).codes.shape == (54, 2)
    assert [bench.board.bus.ports[k].properties[PROP_SERIAL][0] for k in (1, 2)] == [b"BTSP000000000017",
                                                                                    b"BTSP000000000018"]


def test_a_variant_per_sensor_and_n_sensors_from_the_units(biotac_bridge, biotac_cheetah):
    bench = biotac_bridge(units=[17, "nominal"], variant=["biotac-sp", "biotac"])
    assert [bench.board.sensors[k].variant.name for k in (1, 2)] == ["biotac-sp", "biotac"]
    assert first_frame(bench.port).codes.shape == (44, 2)  # one 19-electrode sensor: the 44-slot frame
    cb = biotac_cheetah(2, units=[17, 18], variant="biotac-sp")
    assert [cb.bus.ports[k].sensor.variant.name for k in (1, 2)] == ["biotac-sp", "biotac-sp"]
    assert cb.bus.ports[2].properties[PROP_SERIAL][0] == b"BTSP000000000018"


# --- 3. a BioTac SP sensor answers its whole frame -----------------------------------------------------------------


def test_an_sp_sensor_answers_e20_to_e24_by_default(biotac_sensor):
    spi = biotac_sensor(variant="biotac-sp", unit=17)
    for i, channel in enumerate(range(36, 41)):  # E20..E24
        _, ok, raw = read_channel(spi, channel, t0=0.05 + 0.01 * i)
        assert ok.all() and not any(w >> 8 == 0xA5 for w in raw), (channel, [hex(w) for w in raw])
    assert spi.properties[PROP_SERIAL][0] == b"BTSP000000000017"  # the serial an SP answers
    assert read_channel(biotac_sensor(), 40)[2][0] == 0xA558  # a 19-electrode sensor has no E24


def test_the_first_arguments_still_go_by_position(biotac_sensor, biotac_bridge):
    from emulator.stimuli import Tap

    spi = biotac_sensor([Tap(0.1, 1.0)], ["PDC"], 3, 17)  # stimuli, channels, seed, unit
    assert spi.sensor.seed == 3 and spi.properties[PROP_SERIAL][0] == b"BTU0000000000017"
    bench = biotac_bridge(2, [Tap(0.1, 1.0)], [17, 18])  # n_sensors, stimuli, units
    assert bench.board.bus.ports[2].properties[PROP_SERIAL][0] == b"BTU0000000000018"


# --- 2. scene= on every factory ---------------------------------------------------------------------------------


def test_a_scene_builds_the_bridge_its_sensors_and_their_count(biotac_bridge, sp_scene):
    from bench.cli.scenes import scene_file
    from bench.scenes.scene import load_scene

    bench = biotac_bridge(scene=sp_scene)  # n_sensors: the scene's 2
    assert first_frame(bench.port).codes.shape == (54, 2)
    assert bench.board.sensors[1].params != bench.board.sensors[2].params  # units 17 and 18
    assert bench.board.bus.ports[2].properties[PROP_SERIAL][0] == b"BTSP000000000018"
    taps = biotac_bridge(scene="taps", n_sensors=2)  # a shipped scene by name, as `run` takes it
    assert sorted(taps.board.sensors) == [1, 2]
    assert [taps.board.sensors[k].seed for k in (1, 2)] == [load_scene(scene_file("taps")).seed + k for k in (0, 1)]


def test_a_scene_on_the_sensor_and_the_cheetah_factories(biotac_sensor, biotac_cheetah, sp_scene):
    from bench.scenes.scene import load_scene

    spi = biotac_sensor(scene=sp_scene)
    assert spi.sensor.variant.name == "biotac-sp" and spi.sensor.seed == 5
    assert read_channel(spi, 40)[1].all()  # E24
    cb = biotac_cheetah(scene=load_scene(sp_scene))  # a Scene object
    assert sorted(cb.bus.ports) == [1, 2] and cb.bus.ports[1].properties[PROP_SERIAL][0] == b"BTSP000000000017"


def test_the_module_docstring_lists_every_keyword_the_factories_take():
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.cheetah_server import CheetahBench
    from bench.pytest_plugin import fixtures

    doc = fixtures.__doc__
    keywords = {"scene", "units", "unit", "variant", "channels", "stimuli", "seed", "sensors", "n_sensors",
                *fixtures.SENSOR_KEYWORDS}
    for bench in (FirmwareBench, CheetahBench):
        keywords |= set(inspect.signature(bench).parameters)
    missing = sorted(k for k in keywords if k not in doc)
    assert not missing, f"not in the plugin's docstring: {missing}"


# --- misuse: one clear message, no traceback ----------------------------------------------------------------------

MISUSE = '''
from bench.hosts.cosim import default_sensors

def test_variant_beside_sensors(biotac_bridge):
    biotac_bridge(2, sensors=default_sensors(2), variant="biotac-sp")

def test_n_sensors_against_sensors(biotac_bridge):
    biotac_bridge(3, sensors=default_sensors(2))

def test_no_sensors_given(biotac_cheetah):
    biotac_cheetah(sensors=dict())

def test_bad_scene(biotac_bridge):
    biotac_bridge(scene="{bad}")

def test_unknown_scene_name(biotac_cheetah):
    biotac_cheetah(scene="tapz")

def test_scene_beside_units(biotac_sensor):
    biotac_sensor(scene="taps", unit=17)

def test_too_few_for_the_scene(biotac_bridge):
    biotac_bridge(1, scene="{sp}")

def test_typo(biotac_bridge):
    biotac_bridge(1, realtme=True)

def test_n_sensors_as_a_word(biotac_bridge):
    biotac_bridge(n_sensors="three")

def test_too_many_sensors(biotac_cheetah):
    biotac_cheetah(n_sensors=9)

def test_one_stimulus_not_in_a_list(biotac_sensor):
    from emulator.stimuli import Tap
    biotac_sensor(stimuli=Tap(0.5, 1.0))

def test_a_stimulus_by_name(biotac_bridge):
    biotac_bridge(stimuli=["tap"])

def test_cheetah_on_no_spi_side(biotac_cheetah):
    biotac_cheetah(spi="verilog")

def test_channels_beside_a_scene(biotac_sensor):
    biotac_sensor(scene="taps", channels=["PDC"])

def test_pattern_beside_a_scene(biotac_bridge):
    biotac_bridge(scene="taps", pattern=[0, 1])

def test_units_one_too_many(biotac_bridge):
    biotac_bridge(2, units=[1, 2, 3])

def test_no_sensors(biotac_bridge):
    biotac_bridge(n_sensors=0)

def test_n_sensors_true(biotac_bridge):
    biotac_bridge(n_sensors=True)

kept = []

def test_keeps_the_factory(biotac_bridge):
    kept.append(biotac_bridge)

def test_uses_it_later():
    kept[0](1)
'''


def test_misusing_a_factory_fails_the_test_with_one_clear_message(pytester, tmp_path, sp_scene):
    bad = tmp_path / "bad.toml"
    bad.write_text('[scene]\nname = "bad"\nduration_s = 1.0\n[host]\nsequence = ["PAC", "QQQ"]\n')
    pytester.makepyfile(test_user=MISUSE.format(bad=bad, sp=sp_scene))
    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(failed=19, passed=1)
    out = result.stdout.str()
    result.stdout.fnmatch_lines([
        "*biotac_bridge(): variant given with sensors, which already describes the sensors*",
        "*biotac_bridge(): n_sensors = 3 given with 2 sensors (numbered [[]1, 2[]]); leave n_sensors out*",
        "*biotac_cheetah(): sensors = {}: no sensors on the bus*",
        "*biotac_bridge(): */bad.toml: 1 problem(s):*", '*host.sequence[[]1[]] = "QQQ"*',
        "*biotac_cheetah(): tapz: 1 problem(s):*", "*close matches: taps*",
        "*biotac_sensor(): unit given with scene*",
        "*the scene describes 2 sensors*not 1*",
        "*biotac_bridge(): unknown keyword(s) realtme; it takes*realtime*",
        "*biotac_bridge(): n_sensors = 'three': a whole number from 1 to 5*",
        "*biotac_cheetah(): n_sensors = 9: a whole number from 1 to 5*",
        "*biotac_sensor(): stimuli = Tap(*): give a list of stimuli*",
        "*biotac_bridge(): not a stimulus: 'tap'*",
        '*biotac_cheetah(): spi = \'verilog\': "software" (the Python model) or "rtl" (the Verilog twin)*',
        "*biotac_sensor(): channels given with scene*",
        "*biotac_bridge(): pattern given with scene*",
        "*biotac_bridge(): units = [[]1, 2, 3[]]: give one unit per sensor (2)*",
        "*biotac_bridge(): n_sensors = 0: a whole number from 1 to 5*",
        "*biotac_bridge(): n_sensors = True: a whole number from 1 to 5*",
        "*biotac_bridge(): called after the test it was given to had ended*",
    ])
    assert "Traceback" not in out and "fixtures.py" not in out and "scene.py:" not in out, out


# --- 4. what each keyword does reaches the sensors (a mutation hunt found these unguarded) -------------------------


def test_a_sensor_answers_only_the_channels_it_was_given(biotac_sensor):
    """``channels=["PDC"]``: PDC answers data; PAC, which the sensor no longer provides, an error word (parity
    flag) — the whole frame is the default only."""
    from emulator.channels import PAC, PDC

    only_pdc = biotac_sensor(channels=["PDC"])
    assert read_channel(only_pdc, PDC, t0=0.05)[1].all()
    assert not read_channel(only_pdc, PAC, t0=0.1)[1].any()
    whole = biotac_sensor()
    assert read_channel(whole, PAC)[1].all() and whole.sensor.seed == 0  # the documented default seed


def test_the_benches_sensors_feel_the_stimuli_on_sensor_1_only_and_draw_seed_plus_k():
    """The factories' sensors (``unit_sensors``, what biotac_bridge and biotac_cheetah build): a 2 N, 0.2 s tap raises
    sensor 1's PDC by tens of codes while sensor 2's stays within a few of its rest; sensor k's noise seed is
    ``seed + k - 1``, as a scene's sensor k."""
    from bench.pytest_plugin.fixtures import unit_sensors
    from emulator.channels import PDC
    from emulator.spi.model import SensorPort
    from emulator.stimuli import Tap

    sensors = unit_sensors(2, stimuli=[Tap(0.2, 2.0, duration_s=0.2)], seed=1)
    assert [sensors[k].seed for k in (1, 2)] == [1, 2]
    rise = {}
    for k, sensor in sensors.items():
        port = SensorPort(sensor)
        rest = read_channel(port, PDC, n=5, t0=0.05)[0].mean()
        rise[k] = read_channel(port, PDC, n=5, t0=0.2 + 0.1)[0].mean() - rest
    assert rise[1] > 50 and abs(rise[2]) < 5, rise


def test_a_scenes_sensor_takes_the_seed_given_beside_it(biotac_sensor):
    """``seed`` is the one keyword biotac_sensor takes beside ``scene``: it replaces the scene's seed (the same seed,
    the same codes; another seed, other noise)."""
    from emulator.channels import PAC

    a, b, c = (biotac_sensor(scene="rest", seed=s) for s in (7, 7, 8))
    assert a.sensor.seed == b.sensor.seed == 7 and c.sensor.seed == 8
    codes = [read_channel(p, PAC, n=20)[0] for p in (a, b, c)]
    assert np.array_equal(codes[0], codes[1]) and not np.array_equal(codes[0], codes[2])


def test_a_scenes_cheetah_takes_the_seed_given_beside_it(biotac_cheetah):
    """``seed`` beside a scene on the Cheetah factory replaces the scene's seed: sensor k draws ``seed + k - 1``
    (as on the bridge), and without it the scene's own seed."""
    from bench.cli.scenes import scene_file
    from bench.scenes.scene import load_scene

    given = biotac_cheetah(scene="taps", n_sensors=2, seed=7)
    assert [given.bus.ports[k].sensor.seed for k in (1, 2)] == [7, 8]
    own = biotac_cheetah(scene="taps", n_sensors=2)
    assert [own.bus.ports[k].sensor.seed for k in (1, 2)] == [load_scene(scene_file("taps")).seed + k for k in (0, 1)]


def test_a_scenes_bridge_takes_the_spi_given_beside_it(biotac_bridge):
    """``spi="rtl"`` beside a scene runs the bridge's bus on the Verilog twin (the scene says software)."""
    bench = biotac_bridge(scene="taps", spi="rtl")
    assert bench.board.spi == "rtl" and type(bench.board.bus).__name__ == "RtlBus"
    assert first_frame(bench.port).codes.shape == (44, 1)


@pytest.mark.rtl
def test_a_sensor_without_a_channel_streams_the_same_frames_over_the_rtl_bridge_as_over_the_software(biotac_bridge):
    """Your own sensor built without E7 (``sensors=``) on a bridge with ``spi="rtl"``: the firmware's first two frames
    are those it streams over the software SPI — E7's slot an error (the sensor answered "EX"), every other slot
    data (the RTL bus used to stop the firmware with HarnessError)."""
    from bench.hosts.driver import CMD_START
    from bench.pytest_plugin.fixtures import one_sensor
    from emulator.channels import DEFAULT_FRAME_NAMES, channel_index

    frames = {}
    for spi in ("software", "rtl"):
        sensor = one_sensor(channels=[n for n in DEFAULT_FRAME_NAMES if n != "E7"], seed=2)
        # (host_gone_s: a loaded machine stalling this process longer than the default 0.2 s lost frame 0 once)
        driver = BridgeDriver(biotac_bridge(sensors={1: sensor}, spi=spi, host_gone_s=10.0).port)
        frames[spi] = []
        driver.on_frame(frames[spi].append)  # every frame, also those that came with the acknowledgement
        try:
            driver.start()
            assert driver.wait_for(CMD_START, timeout_s=30) is not None
            for _ in driver.frames(max_frames=2, timeout_s=60):
                if len(frames[spi]) >= 2:
                    break
        finally:
            driver.close()
    e7 = frames["rtl"][0].channels == channel_index("E7")
    assert e7.sum() == 1
    for soft, rtl in zip(frames["software"][:2], frames["rtl"][:2], strict=True):
        assert soft.seq == rtl.seq and np.array_equal(soft.channels, rtl.channels)
        assert np.array_equal(soft.codes, rtl.codes) and np.array_equal(soft.status, rtl.status)
        assert (rtl.status[e7] != 0).all() and (rtl.status[~e7] == 0).all()

"""The pytest plugin as a CI team reads its results: a failing test's report says what each emulated sensor was
and felt (the factory call, each sensor's serial, seed, faults and stimuli, the bench's virtual time), the JUnit XML
carries the same as the test's property ``biotac``, and ``--biotac-spi`` runs every bridge of a session over the
chosen SPI side unless a test says otherwise.  The users' sessions run in subprocesses: in process, a second
session would load numpy's and numba's modules again after pytester unloads them, which they refuse."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import pytest

pytestmark = pytest.mark.firmware
pytest_plugins = ["pytester"]

SEEN = '''
import time

from bench.hosts.driver import BridgeDriver
from emulator.spi.model import Faults
from emulator.stimuli import Tap


def test_fails_after_reading(biotac_bridge, biotac_sensor, biotac_cheetah):
    bench = biotac_bridge(n_sensors=2, stimuli=[Tap(0.3, 1.0)], seed=7)
    bench.now(lambda board: setattr(board.bus.ports[2], "faults", Faults(miso_stuck=1)))
    driver = BridgeDriver(bench.port)
    driver.start()
    frames = list(driver.frames(max_frames=20, timeout_s=20))
    driver.close()
    deadline = time.monotonic() + 20
    while bench.board.bus.ports.get(2) is not None and bench.board.bus.ports[2].faults == Faults():
        assert time.monotonic() < deadline, "the bench never applied the fault"
        time.sleep(0.01)
    biotac_sensor(scene="{scene}", seed=5)
    biotac_cheetah(variant="biotac-sp")
    assert len(frames) == 0, "fails on purpose"


def test_action_raises(biotac_bridge):
    bench = biotac_bridge()
    bench.at(0.05, lambda board: board.bus.ports[7])
    driver = BridgeDriver(bench.port)
    driver.start()
    frames = list(driver.frames(max_frames=30, timeout_s=3))
    driver.close()
    assert len(frames) == 30


def test_passes(biotac_bridge):
    biotac_bridge()


def test_no_sensor():
    assert False
'''

SCENE = '''[scene]
name = "two_taps"
duration_s = 2.0
seed = 3

[[stimulus]]
kind = "tap"
at_s = [0.5, 1.0]
peak_N = 0.5
'''


def test_a_failing_test_says_what_each_sensor_was_and_felt_and_junit_keeps_it(pytester, tmp_path):
    scene = tmp_path / "two_taps.toml"
    scene.write_text(SCENE)
    pytester.makepyfile(test_user=SEEN.format(scene=scene))
    junit = tmp_path / "junit.xml"
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", f"--junitxml={junit}")
    result.assert_outcomes(failed=3, passed=1, errors=1)
    result.stdout.fnmatch_lines([
        "*Captured biotac call*",
        "biotac_bridge(n_sensors=2, stimuli=[[]Tap(*time_s=0.3, peak_N=1.0*)[]], seed=7)",
        "  port /dev/pts/*, SPI side software, virtual time *",
        "  sensor 1: biotac, serial BT0101EMU0000001, seed 7, fidelity default, sensor faults none, SPI faults none",
        "    stimuli: 1",
        "      Tap(indenter_radius_mm=3.0, time_s=0.3, peak_N=1.0, duration_s=0.03)",
        "  sensor 2: biotac, serial BT0101EMU0000002, seed 8, fidelity default, sensor faults none, "
        "SPI faults miso_stuck=1",
        "    stimuli: none",
        f"biotac_sensor(scene='{scene}', seed=5)",
        "  sensor 1: biotac, serial BT0101EMU0000001, seed 5, *",
        "    stimuli: 2",
        "      Tap(indenter_radius_mm=3.0, time_s=0.5, peak_N=0.5, duration_s=0.03)",
        "      Tap(indenter_radius_mm=3.0, time_s=1.0, peak_N=0.5, duration_s=0.03)",
        "biotac_cheetah(variant='biotac-sp')",
        "  socket *cheetah.sock, host time 0.000000 s, 0 batch(es) clocked",
        "  sensor 1: biotac-sp, serial BTSP01EMU0000001, seed 0, *",
    ])
    result.stdout.fnmatch_lines([  # the call's failure says why the stream stopped, not only the teardown
        "*_ test_action_raises _*", "*assert * == 30*", "*Captured biotac call*",
        "  the bench stopped with an error: the action test_action_raises.<locals>.<lambda> at *test_user.py:*, due "
        "at virtual time 0.050000 s, raised KeyError: 7 (virtual time 0.05*", "*short test summary*"])
    out = result.stdout.str()
    assert out.count("Captured biotac") == 3, out  # not for the test that made no sensor (2 for the action's)
    cases = {case.get("name"): case for case in ET.parse(junit).iter("testcase")}
    properties = {name: [p.get("value") for p in case.iter("property") if p.get("name") == "biotac"]
                  for name, case in cases.items()}
    assert properties["test_no_sensor"] == []
    assert properties["test_passes"] == [properties["test_passes"][0]]
    assert properties["test_passes"][0].startswith("biotac_bridge()\n  port /dev/pts/")
    failure = cases["test_fails_after_reading"].find("failure").text  # what a CI page shows of the failure
    assert "AssertionError: fails on purpose" in failure and "SPI faults miso_stuck=1" in failure, failure
    failed = properties["test_fails_after_reading"]
    assert len(failed) == 1 and "SPI faults miso_stuck=1" in failed[0] and "seed 5" in failed[0], failed
    virtual_s = float(re.search(r"SPI side software, virtual time ([0-9.]+) s", failed[0]).group(1))
    assert virtual_s >= 20 * 44 / 4400, failed[0]  # the time the bench had reached: 20 frames of 44 slots read


SPI_SIDE = '''
def test_default(biotac_bridge):
    assert biotac_bridge().board.spi == "{default}"

def test_scene_asks_for_rtl(biotac_bridge):
    assert biotac_bridge(scene="{rtl_scene}").board.spi == "{scene}"

def test_the_call_decides(biotac_bridge):
    assert biotac_bridge(spi="software").board.spi == "software"

SIDE = {{"SensorPort": "software", "HarnessPeripheral": "rtl"}}
started = []

def test_sensor_default(biotac_sensor):
    assert SIDE[type(biotac_sensor()).__name__] == "{default}"

def test_sensor_scene_asks_for_rtl(biotac_sensor):
    rtl = biotac_sensor(scene="{rtl_scene}")
    assert SIDE[type(rtl).__name__] == "{scene}"
    started.append(getattr(rtl, "bus", None))

def test_sensor_the_call_decides(biotac_sensor):
    assert type(biotac_sensor(spi="software")).__name__ == "SensorPort"
    rtl = biotac_sensor(spi="rtl")
    assert type(rtl).__name__ == "HarnessPeripheral" and rtl.bus.proc.poll() is None
    started.append(rtl.bus)

def test_cheetah_default(biotac_cheetah):
    assert biotac_cheetah().spi == "{default}"

def test_cheetah_scene_asks_for_rtl(biotac_cheetah):
    rtl = biotac_cheetah(scene="{rtl_scene}")
    assert rtl.spi == "{scene}"
    started.append(getattr(rtl.bus, "proc", None) and rtl.bus)

def test_cheetah_the_call_decides(biotac_cheetah):
    assert biotac_cheetah(spi="software").spi == "software"

def test_every_harness_was_stopped_after_its_test():
    assert all(h is None or h.proc.poll() is not None for h in started) and len(started) == 3
'''


@pytest.mark.parametrize("option, default, scene", [(None, "software", "rtl"), ("rtl", "rtl", "rtl"),
                                                    ("software", "software", "software")])
def test_biotac_spi_sets_every_bridges_and_sensors_spi_side_unless_the_call_gives_one(pytester, tmp_path, option,
                                                                                      default, scene):
    """``--biotac-spi`` reaches biotac_bridge, biotac_sensor and biotac_cheetah (a scene's host.spi replaced, a
    call's spi= over both), and every RTL harness a test started is stopped after it."""
    rtl_scene = tmp_path / "rtl.toml"
    rtl_scene.write_text('[scene]\nname = "rtl"\nduration_s = 1.0\n[host]\nspi = "rtl"\n')
    pytester.makepyfile(test_user=SPI_SIDE.format(default=default, scene=scene, rtl_scene=rtl_scene))
    chosen = [] if option is None else [f"--biotac-spi={option}"]
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", *chosen)
    result.assert_outcomes(passed=10)


def test_biotac_spi_refuses_a_side_that_is_not_one(pytester):
    pytester.makepyfile(test_user="def test_x():\n    pass\n")
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "--biotac-spi=verilog")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(["*argument --biotac-spi: invalid choice: 'verilog' (choose from*software*rtl*"])


def unplug_seven(board):
    """An action that fails: there is no sensor 7."""
    return board.bus.ports[7]


@pytest.mark.parametrize("when", ["at", "now"])
def test_an_action_that_raises_stops_the_bench_naming_the_action_its_instant_and_error(when):
    """A test's scheduled action that raises was "the bench failed inside a HAL call: KeyError(7)" (at) or a bare
    "KeyError(7)" (now), naming neither the action nor where it is written."""
    from bench.errors import ActionError
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.driver import BridgeDriver

    bench = FirmwareBench().start()
    driver = BridgeDriver(bench.port)
    try:
        if when == "at":
            bench.at(0.05, unplug_seven)
        else:
            bench.now(unplug_seven)
        driver.start()
        list(driver.frames(max_frames=30, timeout_s=3))
        bench._thread.join(60)  # (the action stops it: from a cold start the first frames can take the 3 s)
    finally:
        driver.close()
    where = f"unplug_seven at {__file__}:{unplug_seven.__code__.co_firstlineno}"
    instant = "due at virtual time 0.050000 s" if when == "at" else "asked to run now"
    with pytest.raises(RuntimeError, match=re.escape(f"the action {where}, {instant}, raised KeyError: 7 (virtual "
                                                     "time ")) as stopped:
        bench.stop()
    assert isinstance(stopped.value.__cause__, ActionError), repr(stopped.value.__cause__)
    assert "HAL call" not in str(stopped.value)  # the test's action, not the firmware's HAL, failed
    # its message as written, not inside the repr of an ActionError('…') (which escaped its quotes)
    assert str(stopped.value) == f"the firmware bench stopped with an error: {stopped.value.__cause__}"


def test_a_slide_is_described_by_its_textures_name_not_by_the_whole_texture():
    """A slide's texture and skin are records of many fields (a spectrum, friction, the ridges): the report names
    the texture and leaves the skin's fields out, so the slide's own fields fit the line."""
    from bench.hosts.scene_sensors import sensors_from_scene
    from bench.pytest_plugin.fixtures import load_scene_like
    from bench.pytest_plugin.hooks import MAX_VALUE_CHARS, stimulus_text

    sensor = sensors_from_scene(load_scene_like("slip_onset"), 1)[1]
    (slide,) = [s for s in sensor.stimuli if type(s).__name__ == "Slide"]
    text = stimulus_text(slide)
    assert text.startswith(f"Slide(start_s={slide.start_s!r}, texture=Texture({slide.texture.name!r}), "
                           f"force_N={slide.force_N!r}, "), text
    assert text.endswith(", skin=Skin(…))") and len(text) <= MAX_VALUE_CHARS, text


KEPT = '''
import gc
import weakref

import pytest

MADE = []


@pytest.mark.parametrize("i", range(3))
def test_makes(biotac_sensor, biotac_bridge, i):
    MADE.extend(weakref.ref(x) for x in (biotac_sensor(), biotac_sensor().sensor, biotac_bridge()))
    assert i != 1, "fails on purpose: described, then let go too"


def test_after():
    gc.collect()
    assert len(MADE) == 9 and [r() for r in MADE] == [None] * 9
'''


def test_what_a_test_made_is_let_go_once_its_report_is_made(pytester):
    """pytest keeps every test item to the session's end: the sensors and benches a test's factories made, kept on
    its item for the report, were kept with it (every sensor of a suite in memory at once, ~0.3 MB each and more
    with its signals); once the test's teardown is reported they are let go, failed or passed."""
    pytester.makepyfile(test_user=KEPT)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider")
    result.assert_outcomes(passed=3, failed=1)
    result.stdout.fnmatch_lines(["*Captured biotac call*"])


def test_a_stimulus_built_from_numpy_numbers_is_described_by_their_values():
    """A test that builds its stimuli from numpy arrays reads the numbers in the report as if it had typed them
    (``peak_N=1.5``), not numpy's ``np.float64(1.5)`` nor ``float32(…)``, which hid the value."""
    import numpy as np

    from bench.pytest_plugin.hooks import stimulus_text
    from emulator.stimuli import Press, Tap

    assert stimulus_text(Tap(np.float64(0.3), np.float32(1.5), np.float16(0.25))) == stimulus_text(Tap(0.3, 1.5, 0.25))
    assert stimulus_text(Press(*np.array([0.1, 1.0, 0.5, 2.0]))) == stimulus_text(Press(0.1, 1.0, 0.5, 2.0))
    assert stimulus_text(Tap(np.int64(1), np.uint8(3))) == stimulus_text(Tap(1, 3))


def test_the_serial_port_has_no_modem_lines_as_the_readme_says(biotac_serial_port):
    """README (Serial link): pyserial opens the pty and reads frames, but setting DTR or RTS, or reading CD, CTS or
    DSR, fails with ENOTTY — a driver that toggles DTR meets that here, not on a USB bridge."""
    import errno

    import serial

    from bench.hosts.driver import CMD_START, encode

    port = serial.Serial(biotac_serial_port, 3_000_000, timeout=2)
    try:
        for line in ("dtr", "rts"):
            with pytest.raises(OSError) as refused:
                setattr(port, line, False)
            assert refused.value.errno == errno.ENOTTY
        for line in ("cd", "cts", "dsr"):
            with pytest.raises(OSError) as refused:
                getattr(port, line)
            assert refused.value.errno == errno.ENOTTY
        port.write(encode(CMD_START))
        assert port.read(2) == b"\xaa\x55"  # the port still works: the START was answered
    finally:
        port.close()


def test_biotac_sensor_over_the_rtl_answers_as_the_software_model_and_takes_its_spi_faults(biotac_sensor):
    """``biotac_sensor(spi="rtl")``: the Verilog twin behind the same ``exchange``, the same words, and
    ``spi.faults = Faults(...)`` works on it as on the software port (it had no ``faults``: the setting did
    nothing)."""
    import numpy as np

    from bench.pytest_plugin.hooks import describe
    from emulator.rtl.harness import HarnessPeripheral
    from emulator.spi import protocol as proto
    from emulator.spi.model import Faults, SensorPort
    from emulator.spi.peripheral import TransferBatch
    from emulator.stimuli import Tap

    def reads(t0_s: float, n: int = 100) -> TransferBatch:
        """``n`` PDC samples from ``t0_s`` at 1 kHz: each a sampling command, then a read 60 µs later."""
        start = np.repeat(t0_s + np.arange(n) * 1e-3, 2) + np.tile([0.0, 60e-6], n)
        mosi = np.tile(np.array([int(proto.sample_command(1)) << 8, 0], np.uint16), n)
        return TransferBatch(start, mosi)

    software, rtl = (biotac_sensor(stimuli=[Tap(0.05, 1.0)], spi=side) for side in ("software", "rtl"))
    assert isinstance(software, SensorPort) and isinstance(rtl, HarnessPeripheral)
    assert [describe("biotac_sensor", "call", port).splitlines()[1] for port in (software, rtl)] == [
        "  SPI side software", "  SPI side rtl"]  # what a failing test's report says of each
    clean = rtl.exchange(reads(0.001))  # (not at 0 s: a word starting at power-on reads 0x255F over the RTL)
    assert np.array_equal(clean, software.exchange(reads(0.001)))
    values, ok = proto.decode_response(clean[1::2])
    assert ok.all() and values.max() - values.min() > 20  # the tap, read over the RTL
    for port in (software, rtl):
        port.faults = Faults(miso_stuck=1)
    stuck = rtl.exchange(reads(0.2))
    assert np.array_equal(stuck, software.exchange(reads(0.2))) and (stuck == 0xFFFF).all()
    with pytest.raises(ValueError, match="must be an emulator.spi.model.Faults"):
        rtl.faults = "stuck"
    with pytest.raises(pytest.fail.Exception, match=re.escape('''biotac_sensor(): spi = 'verilog': "software" (the '''
                                                              '''Python model) or "rtl" (the Verilog twin)''')):
        biotac_sensor(spi="verilog")


@pytest.mark.parametrize("spi", ["", 0, False])
def test_biotac_sensor_refuses_an_spi_side_that_is_no_name_rather_than_running_the_software_model(biotac_sensor,
                                                                                                    spi):
    """``biotac_sensor(spi="")`` (or 0, False) names the two sides, as ``biotac_bridge(spi="")`` does; it had been
    taken for "not given" and ran the software model without a word."""
    with pytest.raises(pytest.fail.Exception, match=re.escape(f'biotac_sensor(): spi = {spi!r}: "software" (the '
                                                              f'Python model) or "rtl" (the Verilog twin)')):
        biotac_sensor(spi=spi)

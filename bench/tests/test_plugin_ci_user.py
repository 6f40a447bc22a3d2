"""The pytest plugin as a firmware team's CI meets it: a factory used without calling it says to call it (it was
"'function' object has no attribute 'exchange'"), ``biotac_bridge(firmware=...)`` runs the team's own firmware and
refuses a missing source in one message, and a firmware that hangs fails the test at teardown naming the hang,
after every bench of the test was stopped — no traceback into the plugin."""

from __future__ import annotations

import pytest

from bench.hosts.cosim import FIRMWARE_DIR

pytestmark = pytest.mark.firmware
pytest_plugins = ["pytester"]

USER_TESTS = '''
import pytest
from bench.hosts import bridge
from bench.hosts.driver import BridgeDriver

HANG = """
    if (b->streaming && b->hal->micros(b->hal->ctx) > 50000) {{ for (;;) {{ (void)b->hal->micros(b->hal->ctx); }} }}
"""

def own(tmp_path, extra=""):
    src = tmp_path / "mine.c"
    step = "void bt_step(bt_bridge *b) {{\\n    serve_host(b);\\n"
    src.write_text(open("{reference}").read().replace(step, step + extra))
    return src

def test_sensor_factory_used_uncalled(biotac_sensor):
    biotac_sensor.exchange

def test_bridge_factory_used_uncalled(biotac_bridge):
    biotac_bridge.port

def test_own_firmware_streams(biotac_bridge, tmp_path):
    bench = biotac_bridge(firmware=[own(tmp_path)])
    driver = BridgeDriver(bench.port)
    driver.start()
    assert len(list(driver.frames(max_frames=10, timeout_s=10))) == 10
    driver.close()

def test_missing_source(biotac_bridge, tmp_path):
    biotac_bridge(firmware=[tmp_path / "nope.c"])

def test_hung_firmware(monkeypatch, biotac_bridge, tmp_path):  # monkeypatch first: undone after the bench stops
    monkeypatch.setattr(bridge, "STOP_TIMEOUT_S", 0.3)
    healthy = biotac_bridge()
    hung = biotac_bridge(firmware=[own(tmp_path, HANG)])
    driver = BridgeDriver(hung.port)
    driver.start()
    assert len(list(driver.frames(max_frames=3, timeout_s=10))) == 3
    assert len(list(driver.frames(max_frames=100, timeout_s=1))) < 10  # the stream stops: hung at 0.05 s
    driver.close()
    pytest.hung_benches = (healthy, hung)

def test_after_hung():
    healthy, hung = pytest.hung_benches
    assert healthy.link.closed and hung.link.closed  # both stopped, the healthy one too
'''


def test_a_ci_users_mistakes_and_own_firmware_get_one_clear_message_each(pytester):
    pytester.makepyfile(test_user=USER_TESTS.format(reference=FIRMWARE_DIR / "bt_bridge.c"))
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider")  # the hung thread ends with its process
    result.assert_outcomes(passed=3, failed=3, errors=1)
    for line in ("*AttributeError: biotac_sensor is a factory fixture, not a sensor's SPI side: call it first, e.g. "
                 "x = biotac_sensor()*then x.exchange",
                 "*AttributeError: biotac_bridge is a factory fixture, not a FirmwareBench: call it first*then x.port",
                 "*biotac_bridge(): the firmware: source '*nope.c' is not a file*"):
        result.stdout.fnmatch_lines([line])
    result.stdout.fnmatch_lines([
        "*ERROR at teardown of test_hung_firmware*",
        "biotac_bridge: bench on /dev/pts/*: the firmware did not return from bt_step within 0.3 s of wall time*",
    ])
    assert "fixtures.py:" not in result.stdout.str()  # no traceback into the plugin

"""The pytest plugin as a user sees it, the record and campaign commands."""

import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from bench.campaigns import faults as campaign
from bench.cli import main as cli

pytestmark = pytest.mark.firmware

USER_TESTS = '''
import numpy as np
import serial
from emulator.spi.peripheral import TransferBatch

def test_with_an_emulated_sensor(biotac_sensor):
    spi = biotac_sensor()
    miso = spi.exchange(TransferBatch(np.array([0.0, 1e-4]), np.array([0x8300, 0x0000], np.uint16)))
    assert miso[1] >> 8 != 0xA5

def test_with_the_firmware_on_a_serial_port(biotac_serial_port):
    port = serial.Serial(biotac_serial_port, 3000000, timeout=2)
    port.write(bytes([0xAA, 0x55, 0x01, 0, 0, 0xAC, 0xFB]))  # START with its CRC-16
    data = port.read(2000)
    port.close()
    assert b"\\xaa\\x55\\x10" in data
'''


def test_the_plugin_hands_user_tests_a_sensor_and_a_serial_port(tmp_path):
    from bench.hosts.driver import crc16

    assert crc16(bytes([0x01, 0, 0])).to_bytes(2, "little") == bytes([0xAC, 0xFB])  # the literal in USER_TESTS
    (tmp_path / "test_user.py").write_text(USER_TESTS)
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(tmp_path)],
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert "2 passed" in out.stdout, out.stdout + out.stderr


def test_record_command_writes_frames_from_a_running_bridge(tmp_path, biotac_bridge):
    fb = biotac_bridge(2)
    out = tmp_path / "rec.npz"
    assert cli.main(["record", fb.port, "--seconds", "0.5", "--out", str(out), "--csv", "--quiet"]) == 0
    data = np.load(out)
    assert data["codes"].shape[1:] == (44, 2) and len(data["seq"]) == 50
    assert (tmp_path / "rec.csv").read_text().startswith("seq,slot,channel,sensor,code,status")


def test_record_reports_a_port_with_nothing_on_it(tmp_path, capsys):
    assert cli.main(["record", "loop://", "--seconds", "0.1", "--out", str(tmp_path / "x.npz"), "--quiet"]) == 2
    assert "no answer to START" in capsys.readouterr().err


def test_campaign_writes_junit_and_fails_a_case_whose_expectation_is_not_met(tmp_path):
    results = campaign.run_campaign(["none", "serial_loss"], ["rest"], [0])
    broken = campaign.FaultCase("never_recovers", "impossible", {}, [], lambda f, s, st: "the check failed")
    results.append(campaign.run_case(broken, "rest", 0, frames_wanted=20))
    path = tmp_path / "c.xml"
    campaign.write_junit(results, path)
    suite = ET.parse(path).getroot()
    assert suite.get("tests") == "3" and suite.get("failures") == "1"
    assert "2 passed, 1 failed" in campaign.summary(results)


def test_the_cheetah_fixture_runs_a_vendor_style_program(biotac_cheetah):
    from bench.hosts.cheetah_server import build_client

    cb = biotac_cheetah(3)
    exe = build_client(cb.library)
    r = subprocess.run([str(exe), "2"], capture_output=True, text=True, env=cb.env, cwd=cb.lib_dir, timeout=60)
    assert r.returncode == 0 and r.stdout.count("BT0101EMU") == 3

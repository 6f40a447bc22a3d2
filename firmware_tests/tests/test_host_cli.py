"""The host-stack commands as users run them (issue 12, items 4 and 6): ``bridge --scene`` honours the whole scene;
``record`` keeps what it received whatever ends it and says how it ended; bad arguments are refused in one line
naming the flag, exit status 2, never a traceback."""

import signal
import subprocess
import time

import numpy as np
import pytest

from bench.hosts.bridge import FirmwareBench
from bench.hosts.driver import CMD_START, CMD_STOP, BridgeDriver, encode
from bench.hosts.scene_sensors import firmware_pattern, sensors_from_scene
from bench.paths import REPO
from bench.scenes.scene import load_scene
from bench.tests.cli_runs import CLI, run_cli
from bench.tests.host_benches import run_firmware

pytestmark = pytest.mark.firmware

BROKEN = """
[scene]
name = "broken"
duration_s = 30
seed = 7
fidelity = "fast"

[sensor]
inflation_volume_mL = 0.8

[noise]
johnson = false
amplifier = false
mains_hum = false
adc = false
spi_coupling = false
thermistor = false

[faults]
electrode_open = [3]
thermistor = "short"

[host]
sequence = ["PAC", "PDC", "E3", "E4", "TDC"]
"""


@pytest.fixture
def broken_scene(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text(BROKEN)
    return path


# --- bridge --scene --------------------------------------------------------------------------------------------


def test_sensors_from_a_scene_carry_its_parameters_faults_noise_fidelity_and_seed(broken_scene):
    scene = load_scene(broken_scene)
    sensors = sensors_from_scene(scene, 3)
    assert [s.seed for s in sensors.values()] == [7, 8, 9]
    for s in sensors.values():
        assert s.params.inflation_volume_mL == 0.8 and s.faults == {"electrode_open": [3], "thermistor": "short"}
        assert s.noise == scene.noise and s.fidelity.name == "fast"
    assert [s.seed for s in sensors_from_scene(scene, 2, seed=100).values()] == [100, 101]
    assert firmware_pattern(scene) == [0, 1, 19, 20, 3]


def test_the_firmware_streams_the_scenes_broken_sensor_not_a_healthy_one(broken_scene):
    scene = load_scene(broken_scene)
    frames = run_firmware(sensors_from_scene(scene, 2), 0.5, pattern=firmware_pattern(scene), status=False).frames
    assert len(frames) > 100
    codes = np.stack([f.codes for f in frames])  # frame, slot, sensor
    assert list(frames[-1].channels) == [0, 1, 19, 20, 3]
    assert (codes[:, 2, :] < 50).all()  # E3 open reads ~0
    assert (codes[:, 3, :] > 1000).all()  # E4 is fine
    assert (codes[:, 4, :] == 4095).all()  # thermistor shorted
    assert codes[:, 0, 0].std() < 0.5  # every noise source off: PAC is flat (the healthy default is 1.4 bits)


@pytest.mark.parametrize("host,says", [
    ("slot_rate_Hz = 3000.0", "host.slot_rate_Hz = 3000"),
    ("spi_clock_Hz = 2e6", "host.spi_clock_Hz = 2e+06: the bridge firmware clocks SPI at 4.4e+06 Hz"),
    ('sequence = ["PDC", "E22"]\n[[sensors]]\nindex = 2\nvariant = "biotac-sp"',  # E22 of the BioTac, sensor 1
     "host.sequence: E22: sensor 1 is a 'biotac', with E1..E19 only"),
], ids=["slot rate", "SPI clock", "E22 of a 19-electrode sensor"])
def test_a_scene_the_firmware_cannot_honour_is_refused_naming_the_field(tmp_path, host, says):
    path = tmp_path / "cannot.toml"
    path.write_text(BROKEN.replace('sequence = ["PAC", "PDC", "E3", "E4", "TDC"]', host))
    r = run_cli("bridge", "--scene", path, "--fast", "--seconds", "1", "--sensors", "2")
    assert r.returncode == 2 and says in r.stderr and "Traceback" not in r.stderr


def test_the_bridge_command_serves_the_scene_and_stops_cleanly_on_sigterm(broken_scene):
    p = subprocess.Popen([*CLI, "bridge", "--scene", str(broken_scene), "--sensors", "2", "--fast"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO)
    try:
        port = None
        deadline = time.monotonic() + 60
        while port is None and time.monotonic() < deadline:
            line = p.stdout.readline()
            if line.startswith("serial port: "):
                port = line.split(": ", 1)[1].strip()
        assert port, p.stderr.read()
        drv = BridgeDriver(port)
        drv.start()
        assert drv.wait_for(CMD_START, timeout_s=10) is not None
        frames = list(drv.frames(max_frames=20, timeout_s=10))
        drv.close()
        assert frames[-1].sensor_mask == 0b11 and list(frames[-1].channels) == [0, 1, 19, 20, 3]
        assert (frames[-1].codes[4] == 4095).all()
        p.send_signal(signal.SIGTERM)
        out, err = p.communicate(timeout=30)
    finally:
        p.kill()
    assert p.returncode == 0, err
    assert "stopped at virtual time" in out and "Traceback" not in err


# --- record: nothing lost, the end reported ----------------------------------------------------------------------


def start_record(port, out, *extra):
    p = subprocess.Popen([*CLI, "record", port, "--out", str(out), *extra], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, cwd=REPO)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        line = p.stderr.readline()
        if line.startswith("recording"):
            return p
        if not line and p.poll() is not None:
            break
    p.kill()
    raise AssertionError(f"record did not start: {p.communicate()}")


@pytest.mark.parametrize("sig,status,word", [(signal.SIGINT, 130, "Ctrl-C"), (signal.SIGTERM, 143, "SIGTERM")])
def test_record_keeps_what_it_received_when_interrupted(tmp_path, sig, status, word):
    out = tmp_path / "rec.npz"
    with FirmwareBench(1, realtime=True) as fb:
        p = start_record(fb.port, out, "--seconds", "600", "--csv")
        time.sleep(1.0)
        p.send_signal(sig)
        stdout, stderr = p.communicate(timeout=30)
    assert p.returncode == status, stderr
    assert "partial recording: interrupted" in stderr or "partial recording: terminated" in stderr
    assert word in stderr and "Traceback" not in stderr
    data = np.load(out)
    assert str(data["end"]) in ("interrupted", "terminated") and float(data["requested_s"]) == 600
    n = len(data["seq"])
    assert 50 <= n <= 300 and data["codes"].shape == (n, 44, 1)
    assert float(data["recorded_s"]) == pytest.approx(n * 0.01)
    assert (tmp_path / "rec.csv").read_text().count("\n") == 1 + n * 44
    assert not list(tmp_path.glob(".*partial"))


def test_record_keeps_what_it_received_when_the_bridge_dies(tmp_path):
    out = tmp_path / "rec.npz"
    fb = FirmwareBench(2, realtime=True).start()
    try:
        p = start_record(fb.port, out, "--seconds", "600")
        time.sleep(1.0)
    finally:
        fb.stop()
    stdout, stderr = p.communicate(timeout=30)
    assert p.returncode == 1, stderr
    assert "warning: partial recording: the bridge went away" in stderr and "Traceback" not in stderr
    data = np.load(out)
    assert str(data["end"]) == "disconnected" and len(data["seq"]) >= 50 and data["codes"].shape[1:] == (44, 2)


def test_record_warns_and_exits_1_when_the_stream_stops_early(tmp_path):
    out = tmp_path / "rec.npz"
    with FirmwareBench(1, realtime=True) as fb:
        p = start_record(fb.port, out, "--seconds", "600", "--idle-timeout", "1")
        time.sleep(1.0)
        fb.board.send_to_firmware(encode(CMD_STOP))  # someone stops the stream; the port stays open
        stdout, stderr = p.communicate(timeout=30)
    assert p.returncode == 1, stderr
    assert "warning: partial recording: no data for 1 s" in stderr
    data = np.load(out)
    assert str(data["end"]) == "stream stopped" and float(data["recorded_s"]) < 600


def test_a_complete_recording_exits_0_and_says_so(tmp_path):
    out = tmp_path / "rec.npz"
    with FirmwareBench(1) as fb:
        r = run_cli("record", fb.port, "--out", out, "--seconds", "0.3", "--quiet")
    assert r.returncode == 0 and "warning" not in r.stderr, r.stderr
    data = np.load(out)
    assert str(data["end"]) == "complete" and len(data["seq"]) == 30


def test_a_record_killed_as_it_writes_leaves_nothing_at_out_and_the_next_record_removes_what_it_left(tmp_path):
    """SIGKILL while the recording is written (its NPZ and CSV under temporary names): nothing half-written under
    --out or the CSV's name; the next record to that --out removes the temporary files, says so, and writes both."""
    out = tmp_path / "rec.npz"

    def temps():
        return sorted(p.name for p in tmp_path.iterdir() if p.name.endswith(".part"))

    for _ in range(5):  # (a kill that comes before the writing or after the renaming leaves nothing: tried again)
        with FirmwareBench(1) as fb:  # not paced: frames come as fast as the record reads them
            p = subprocess.Popen([*CLI, "record", fb.port, "--out", str(out), "--seconds", "30", "--csv", "--quiet"],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=REPO)
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline and p.poll() is None and not temps():
                time.sleep(0.001)
            p.send_signal(signal.SIGKILL)
            p.wait()
        if temps() and not out.exists():
            break
        for f in tmp_path.iterdir():
            f.unlink()
    left = temps()
    assert left and not out.exists() and not (tmp_path / "rec.csv").exists(), sorted(tmp_path.iterdir())
    with FirmwareBench(1) as fb:
        r = run_cli("record", fb.port, "--out", out, "--seconds", "0.3", "--quiet", "--csv")
    assert r.returncode == 0, r.stderr
    note = [line for line in r.stderr.splitlines() if line.startswith("note: ")]
    assert len(note) == 1 and f"--out {out}: removed " in note[0] and "interrupted record" in note[0], r.stderr
    assert all(name in note[0] for name in left)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv", "rec.npz"]
    assert len(np.load(out)["seq"]) == 30


def test_record_clears_what_an_earlier_host_left_unread_before_it_sends_start(tmp_path):
    """README: what an earlier host left unread is cleared first. A port whose far end never answers but holds an
    earlier host's unread ACK to START (a bridge hung since): record must not take that ACK for its own START's, and
    says no answer came (exit 2, a bad port) instead of recording an empty stream from a dead bridge."""
    import os

    from bench.hosts.driver import T_ACK

    master, slave = os.openpty()
    try:
        os.write(master, encode(T_ACK, bytes([CMD_START, 0])))
        r = run_cli("record", os.ttyname(slave), "--out", tmp_path / "rec.npz", "--seconds", "0.3", "--quiet")
    finally:
        os.close(master)
        os.close(slave)
    assert r.returncode == 2 and "no answer to START within 5 s" in r.stderr, r.stderr
    assert not (tmp_path / "rec.npz").exists()


def test_a_recording_across_a_sensor_loss_is_saved_by_sensor_number(tmp_path):
    """The set of sensors changes mid-recording (sensor 2 unplugged): the file indexes codes by sensor number."""
    from bench.cli.hosts import _save_recording
    from bench.hosts.driver import DataFrame as F

    ch = np.array([0, 1])
    frames = [F(0, 0b11, ch, np.array([[1, 2], [3, 4]], np.uint16), np.zeros((2, 2), np.uint8)),
              F(1, 0b01, ch, np.array([[5], [6]], np.uint16), np.zeros((2, 1), np.uint8))]
    _save_recording(tmp_path / "r.npz", frames, {"end": "complete"}, csv=False)
    d = np.load(tmp_path / "r.npz")
    assert str(d["layout"]) == "by_sensor" and d["codes"].shape == (2, 2, 5)
    assert d["codes"][1, :, 0].tolist() == [5, 6] and (d["status"][1, :, 1] == 255).all()


# --- bad arguments: one line naming the flag, exit status 2 --------------------------------------------------------

BAD = [
    (("bridge", "--speed", "0"), "--speed"),
    (("bridge", "--speed", "-1"), "--speed"),
    (("bridge", "--speed", "nan"), "--speed"),
    (("bridge", "--speed", "inf"), "--speed"),
    (("bridge", "--speed", "fast"), "--speed"),
    (("bridge", "--sensors", "0"), "--sensors"),
    (("bridge", "--sensors", "6"), "--sensors"),
    (("bridge", "--sensors", "two"), "--sensors"),
    (("bridge", "--seconds", "0"), "--seconds"),
    (("bridge", "--seconds", "-3"), "--seconds"),
    (("bridge", "--seed", "-1"), "--seed"),
    (("bridge", "--seed", "1.5"), "--seed"),
    (("bridge", "--baud", "0"), "--baud"),
    (("bridge", "--rx-buffer", "10"), "--rx-buffer"),
    (("bridge", "--scene", "no/such/scene.toml"), "--scene"),
    (("bridge", "--scene", "fixtures"), "--scene"),
    (("bridge", "--spi", "verilog"), "--spi"),
    (("record", "loop://", "--seconds", "0"), "--seconds"),
    (("record", "loop://", "--seconds", "-1"), "--seconds"),
    (("record", "loop://", "--seconds", "nan"), "--seconds"),
    (("record", "loop://", "--seconds", "1e99"), "--seconds"),
    (("record", "loop://", "--baud", "0"), "--baud"),
    (("record", "loop://", "--baud", "-9600"), "--baud"),
    (("record", "loop://", "--baud", "fast"), "--baud"),
    (("record", "loop://", "--baud", "9600.5"), "--baud"),
    (("record", "loop://", "--idle-timeout", "0"), "--idle-timeout"),
    (("record", "loop://", "--out", "fixtures"), "--out"),
    (("record", "loop://", "--out", "README.md/x.npz"), "--out"),
    (("record", "/dev/no-such-port", "--seconds", "1"), "port"),
    (("campaign", "--seeds", "-1"), "--seeds"),
    (("campaign", "--seeds", "0"), "--seeds"),
    (("campaign", "--seeds", "many"), "--seeds"),
    (("campaign", "--faults", "meteor_strike"), "--faults"),
    (("campaign", "--scenes", "moon"), "--scenes"),
    (("campaign", "--faults", ""), "--faults"),
    (("campaign", "--junit", "fixtures"), "--junit"),
    (("cheetah", "serve", "--sensors", "0"), "--sensors"),
    (("cheetah", "serve", "--sensors", "9"), "--sensors"),
    (("cheetah", "serve", "no/such.toml"), "scene"),
    (("cheetah", "serve", "--seed", "-2"), "--seed"),
    (("cheetah", "serve", "--seconds", "0"), "--seconds"),
    (("rtl", "stream", "--seconds", "0"), "--seconds"),
    (("rtl", "vectors", "README.md"), "files"),
    (("rtl", "vectors", "no/such/vectors.json"), "files"),
]


def invoke(args, capsys) -> tuple[int, str]:
    """Run the CLI in process (as the entry point does): exit status and what it wrote to stderr."""
    from bench.cli import main as cli

    try:
        status = cli.main([str(x) for x in args])
    except SystemExit as e:
        status = e.code
    return status, capsys.readouterr().err


@pytest.mark.parametrize("args,flag", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_arguments_are_refused_in_one_line_naming_the_flag(args, flag, capsys):
    status, err = invoke(args, capsys)
    lines = [line for line in err.splitlines() if line.strip()]
    assert status == 2, (status, err)
    assert len(lines) == 1 and flag in lines[0], err
    assert "Traceback" not in err


@pytest.mark.parametrize("args", [BAD[0][0], BAD[17][0], BAD[29][0]], ids=lambda a: " ".join(a))
def test_the_entry_point_refuses_them_the_same_way(args):
    r = run_cli(*args, timeout=60)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr


def test_a_campaign_with_nothing_to_run_is_refused_not_passed():
    from bench.campaigns import faults as campaign

    for faults, scenes, seeds in (([], ["rest"], [0]), (["none"], [], [0]), (["none"], ["rest"], range(-1))):
        with pytest.raises(ValueError, match="vacuously"):
            campaign.run_campaign(faults, scenes, seeds)
    with pytest.raises(ValueError, match="unknown fault or scene: meteor"):
        campaign.run_campaign(["meteor"], ["rest"], [0])


def test_a_slow_hosts_recording_starts_with_the_first_frame_after_start(tmp_path, monkeypatch):
    """A host slow to read START's ACK (here: until three frames wait behind it in the receive buffer; the bench
    unpaced, so nothing overruns however long the first run's compilation takes) records from the first frame on —
    seq 0, none missing.  Those frames arrive with the ACK; ``record`` forgot them, uncounted, as if an earlier
    session's, and started late without a word."""
    from bench.cli import main as cli

    slow = BridgeDriver.wait_for

    def wait_for_slowly(self, *args, **kwargs):
        deadline = time.monotonic() + 60
        while self.serial.in_waiting < 9 + 3 * 143 and time.monotonic() < deadline:  # the ACK, 3 frames
            time.sleep(0.005)
        waiting.append(self.serial.in_waiting)
        return slow(self, *args, **kwargs)

    with FirmwareBench(1) as warm:  # the sensor model compiled first (cold caches take seconds, and a reply later
        drv = BridgeDriver(warm.port)  # than the driver's 5 s horizon is taken as lost)
        drv.start()
        assert next(drv.frames(max_frames=1, timeout_s=120)).seq == 0
        drv.close()
    waiting = []
    monkeypatch.setattr(BridgeDriver, "wait_for", wait_for_slowly)
    out = tmp_path / "rec.npz"
    with FirmwareBench(1) as fb:
        assert cli.main(["record", fb.port, "--out", str(out), "--seconds", "0.5", "--quiet"]) == 0
    data = np.load(out)
    assert waiting[0] >= 9 + 3 * 143  # the ACK and frames behind it were waiting
    assert data["seq"].tolist() == list(range(50)) and int(data["dropped_frames"]) == 0

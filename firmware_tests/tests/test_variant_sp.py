"""The BioTac SP through the bridge firmware, the host driver and the Cheetah path.

The firmware recognises an SP by its "BTSP" serial, streams the 54-slot frame when every sensor present is an SP,
and reports E20..E24 asked of a 19-electrode BioTac as error words (status 2), which the driver never hands out as
codes.  Runs the firmware natively in virtual time (in-memory UART, no threads) so the streams are deterministic.
"""

import numpy as np
import pytest

from bench.hosts.cosim import default_sensors
from bench.tests.host_benches import run_firmware
from emulator import channels as ch
from emulator.spi import protocol as proto

pytestmark = pytest.mark.firmware
SP = ch.variant("biotac-sp")


def test_an_sp_streams_the_54_slot_frame_with_data_in_every_slot():
    run = run_firmware(default_sensors(1, seed=3, variant="biotac-sp"), 0.5)
    frames, status = run.frames, run.status
    assert len(frames) >= 40
    for f in frames:
        assert [ch.variant("biotac-sp").channel_name[c] for c in f.channels] == list(SP.frame_names)
        assert f.codes.shape == (54, 1) and f.ok.all()
    assert status.sp_mask == 1 and status.sp_sensors == [1] and status.error_words == 0
    e = frames[-1].samples(1)
    assert all(100 < int(e[f"E{k}"][0]) < 4000 for k in range(20, 25))


def test_a_biotac_keeps_the_44_slot_frame_and_a_mixed_bus_the_common_one():
    run = run_firmware(default_sensors(1, seed=3), 0.5)
    assert run.frames[-1].codes.shape == (44, 1) and run.status.sp_mask == 0
    mixed = {**default_sensors(1, seed=3), 2: default_sensors(2, seed=3, variant="biotac-sp")[2]}
    run = run_firmware(mixed, 0.5)
    assert run.frames[-1].codes.shape == (44, 2) and run.status.sp_mask == 0b10 and run.frames[-1].ok.all()


def test_vendor_e20_to_e24_on_a_19_electrode_sensor_are_errors_never_data():
    """The SP pattern asked of a BioTac (sensor 1) and an SP (sensor 2) on one bus: the SP's E20..E24 are data,
    the BioTac's are its "EX" error words — status 2, absent from samples(), listed by errors()."""
    mixed = {**default_sensors(1, seed=3), 2: default_sensors(2, seed=3, variant="biotac-sp")[2]}
    run = run_firmware(mixed, 0.3, pattern=SP.frame_names)
    f, status = run.frames[-1], run.status
    names = [ch.variant("biotac-sp").channel_name[c] for c in f.channels]
    bad = [n in {"E20", "E21", "E22", "E23", "E24"} for n in names]
    assert (f.status[bad, 0] == 2).all() and (f.status[~np.array(bad), 0] == 0).all()
    assert f.ok[:, 1].all()
    assert [e[1] for e in f.errors(1)] == [f"E{k}" for k in range(20, 25)] and not f.errors(2)
    assert all(e[2] == "error word" for e in f.errors(1))
    assert "E20" not in f.samples(1) or f.samples(1)["E20"].size == 0
    assert f.samples(2)["E20"].size == 1
    assert status.error_words == 5 * status.frames > 0 and status.parity_errors == 0


@pytest.mark.rtl
def test_sp_frames_are_identical_over_the_software_model_and_the_rtl():
    """Same sensors, same seed, same firmware: the 54-slot frames from the software bus and the Verilog bus."""
    a = run_firmware(default_sensors(1, seed=5, variant="biotac-sp"), 0.25).frames
    b = run_firmware(default_sensors(1, seed=5, variant="biotac-sp"), 0.25, spi="rtl").frames
    assert len(a) == len(b) >= 20
    for x, y in zip(a, b):
        assert x.seq == y.seq and np.array_equal(x.codes, y.codes) and np.array_equal(x.status, y.status)
    assert a[0].codes.shape == (54, 1)


# --- a scene's host.sequence with E20..E24 as the firmware's pattern (bridge --scene) -----------------------------------
E20_E24 = ["E20", "E21", "E22", "E23", "E24"]
SEQUENCE = '[host]\nsequence = ["E20", "E21", "E22", "E23", "E24", "PDC"]\n'
#: two SPs (unit 5 and the nominal one); sensor 1 is pressed over E22 from 0.1 s
SP_SCENE = ('[scene]\nname = "sp"\nduration_s = 0.5\n[sensor]\nvariant = "biotac-sp"\nunit = 5\n'
            '[[sensors]]\nindex = 2\nvariant = "biotac-sp"\n'
            '[[stimulus]]\nkind = "touch"\nelectrode = "E22"\nstart_s = 0.1\nforce_N = 1.0\nramp_s = 0.05\n'
            'hold_s = 0.3\n'  # the touch ends (0.5 s) with the scene: a stimulus must end within it
            '[noise]\nadc = false\nspi_coupling = false\n' + SEQUENCE)


def test_a_scene_sampling_e20_to_e24_of_sp_sensors_gets_their_data_through_the_firmware():
    from bench.hosts.scene_sensors import firmware_pattern, sensors_from_scene
    from bench.scenes.scene import parse_scene_text

    sc = parse_scene_text(SP_SCENE)
    pattern = firmware_pattern(sc)
    assert pattern == [36, 37, 38, 39, 40, 1]  # E20..E24 = channels 36..40, then PDC
    run = run_firmware(sensors_from_scene(sc, 2), 0.4, pattern=pattern)
    assert len(run.frames) >= 250 and run.status.sp_mask == 0b11
    assert run.status.error_words == 0 and run.status.parity_errors == 0
    for f in run.frames:
        assert [SP.channel_name[c] for c in f.channels] == [*E20_E24, "PDC"]
        assert f.ok.all() and ((f.codes > 100) & (f.codes < 4000)).all()
    codes = {k: {n: np.array([f.samples(k)[n][0] for f in run.frames], float) for n in E20_E24} for k in (1, 2)}
    e22 = codes[1]["E22"]
    assert e22[:30].mean() - e22[-30:].mean() > 100  # sensor 1's own E22 feels the press over it
    assert all(np.ptp(c) <= 3 for c in codes[2].values())  # sensor 2 feels nothing


def test_a_scene_sampling_e20_to_e24_of_a_19_electrode_sensor_is_refused_naming_them_and_its_variant():
    """E20..E24 on a bus with 19-electrode sensors: the scene is valid for ``run`` (the SP reads them), but the
    firmware's one pattern would ask the BioTacs too, which have no such electrodes."""
    from bench.errors import SceneError
    from bench.hosts.scene_sensors import firmware_pattern
    from bench.scenes.scene import parse_scene_text

    head = '[scene]\nname = "mixed"\nduration_s = 0.5\n[sensor]\nunit = 5\n'
    sp = '[[sensors]]\nindex = {k}\nvariant = "biotac-sp"\n'
    sc = parse_scene_text(head + sp.format(k=2) + SEQUENCE)
    with pytest.raises(SceneError, match=r"host.sequence: E20, E21, E22, E23, E24: sensor 1 is a 'biotac', "
                                         r"with E1..E19 only.*every sensor is a \"biotac-sp\""):
        firmware_pattern(sc)
    sc = parse_scene_text(head + '[[sensors]]\nindex = 3\n' + sp.format(k=2) + SEQUENCE.replace('"E20", ', ''))
    with pytest.raises(SceneError, match=r"host.sequence: E21, E22, E23, E24: sensors 1, 3 are each a 'biotac'"):
        firmware_pattern(sc)
    sc = parse_scene_text(head)
    sc.sequence = ["PDC", "E24"]  # set by a program (a scene file with only BioTacs is refused at parse)
    with pytest.raises(SceneError, match=r"host.sequence: E24: sensor 1 is a 'biotac'"):
        firmware_pattern(sc)


# --- the same codes through every path -------------------------------------------------------------------------------
class Recording:
    """A sensor that logs every conversion it is asked for (channels, instants, bus activity, codes)."""

    def __init__(self, sensor):
        self.sensor, self.log = sensor, []

    def __getattr__(self, name):
        return getattr(self.sensor, name)

    def sample(self, channels, times, bus_active=None):
        codes = self.sensor.sample(channels, times, bus_active)
        n = np.size(times)
        active = np.zeros(n, bool) if bus_active is None else np.broadcast_to(np.asarray(bus_active, bool), (n,))
        self.log.append((np.array(channels, np.int64).ravel(), np.array(times, float).ravel(), active.copy(),
                         np.array(codes).ravel()))
        return codes

    def conversions(self):
        """(channels, instants s, bus activity, codes) of every conversion so far, in time order."""
        c, t, a, k = (np.concatenate(x) for x in zip(*self.log))
        order = np.argsort(t, kind="stable")
        return c[order], t[order], a[order], k[order]


def pressed_sp():
    """An SP pressed (2 N) over E22 from t = 0, noise on: the electrodes' codes differ from each other (E22 far
    below the rest), so a path that loses, swaps or mislabels a slot shows."""
    from emulator.sensor import Sensor
    from emulator.stimuli import Touch

    return Sensor(stimuli=[Touch(0.0, 2.0, ramp_s=0.01, hold_s=1000.0, electrode="E22")], channels_read=SP.frame_names,
                  variant="biotac-sp", seed=3)


def check_against_a_fresh_model(rec: Recording):
    """The conversions the path asked for, recomputed by a fresh software model in one call: the same codes
    (the model's results do not depend on how the instants are batched)."""
    c, t, a, k = rec.conversions()
    assert np.array_equal(pressed_sp().sample(c, t, bus_active=a), k)
    return c, k


def streamed_codes(frames):
    return np.concatenate([f.channels for f in frames]), np.concatenate([f.codes[:, 0] for f in frames])


@pytest.mark.parametrize("spi", ["software", pytest.param("rtl", marks=pytest.mark.rtl)])
def test_the_54_slot_frame_reaches_the_host_with_the_software_models_codes(spi):
    """Firmware + driver (over the software bus or the Verilog one): every code the host receives, slot by slot,
    is the code the software model gives for that channel at that conversion instant."""
    rec = Recording(pressed_sp())
    frames = run_firmware({1: rec}, 0.3, spi=spi).frames
    c, k = check_against_a_fresh_model(rec)
    ch_host, codes_host = streamed_codes(frames)
    n = codes_host.size
    assert n >= 20 * 54 and frames[0].codes.shape == (54, 1)
    assert np.array_equal(c[:n], ch_host) and np.array_equal(k[:n], codes_host)
    e22 = codes_host[ch_host == SP.channel_index["E22"]]
    assert np.median(e22) < np.median(codes_host[ch_host == SP.channel_index["E10"]]) - 300  # the press shows


def test_a_vendor_style_cheetah_client_gets_sp_data_and_clear_errors_from_a_19_electrode_sensor(tmp_path):
    """The Cheetah client sampling the SP frame (E20..E24 = 0xC8..0xD0) from an SP (sensor 1) and a BioTac
    (sensor 2): the SP's words carry the software model's codes slot by slot; the BioTac's E20..E24 are 0xA558
    (parity flag set), counted as error words, never as samples."""
    import subprocess

    from emulator.sensor import Sensor
    from bench.hosts.cheetah_server import CheetahBench, build_client

    biotac = Sensor(channels_read=ch.DEFAULT_FRAME_NAMES, seed=4)
    rec = Recording(pressed_sp())
    dump = tmp_path / "words.txt"
    with CheetahBench(sensors={1: rec, 2: biotac}) as cb:
        exe = build_client(cb.library)
        r = subprocess.run([str(exe), "1", "sp", str(dump)], capture_output=True, text=True, env=cb.env, timeout=120)
        assert r.returncode == 0, r.stderr
    serials = [line.split()[-1] for line in r.stdout.splitlines() if line.startswith("serial")]
    assert serials[0].startswith("BTSP") and serials[1].startswith("BT0101")
    fields = r.stdout.splitlines()[-1].split()
    stats = dict(zip(fields[::2], fields[1::2]))
    assert stats["frames"] == "5" and stats["parity_errors"] == "0" and stats["error_words"] == str(5 * 5)
    rows = [line.split() for line in dump.read_text().splitlines()]
    words = {(int(s), int(i)): (int(c, 16), int(w, 16)) for i, s, c, w in rows}
    sp_words = np.array([words[1, i][1] for i in range(5 * 54)], np.uint16)  # the first batch: 5 frames
    value, ok = proto.decode_response(sp_words)
    c, k = check_against_a_fresh_model(rec)
    assert ok.all() and np.array_equal(c[:270], np.tile(ch.parse_sequence("default", "biotac-sp"), 5))
    assert np.array_equal(value, k[:270])
    vendor = [words[2, k] for k in range(54) if SP.frame_names[k] in {"E20", "E21", "E22", "E23", "E24"}]
    assert [cmd for cmd, _ in vendor] == [0xC8, 0xCB, 0xCD, 0xCE, 0xD0]
    assert all(w == proto.ERROR_WORDS["channel_not_recognized"] for _, w in vendor)
    assert not proto.decode_response(np.array([w for _, w in vendor], np.uint16))[1].any()

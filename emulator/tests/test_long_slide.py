"""A long slide's memory does not grow with its length (issue 8, hard cases: "a 10-minute slide without drift in
energy or memory").  A track's texture tables (patch-averaged heights, ridge slopes, friction fluctuation) are
computed whole for a track of up to TABLE_WHOLE_MAX positions, as they always were (a short slide's samples are
those saved before the change, to the bit); a longer one is held as a ring of tiles around the finger, refilled as
the stage moves on.  The ring gives the same samples for any ring size, margin and block size, and the whole
table's codes; a 10-minute slide at 10 cm/s (60 m, the 1 m texture track wrapping 60 times) peaks within 20 % +
30 MB of a short slide's memory and its PAC power stays constant minute after minute."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import emulator.sliding as sliding
from emulator.channels import PAC, PDC
from emulator.sensor import Sensor
from emulator.sliding import Slide
from emulator.texture import PeriodicComponent, Texture

SAND = Texture(901, "sand", "test", rms_height_m=60e-6, correlation_length_m=270e-6, hurst=0.8, mu_static=0.9,
               mu_kinetic=0.6, modulus_Pa=5e9, seed=7)
GRATING = Texture(902, "grating", "test", rms_height_m=0.5e-6, correlation_length_m=100e-6, hurst=0.8,
                  mu_static=0.6, mu_kinetic=0.45, seed=8,
                  periodic=(PeriodicComponent(3e-3, 250e-6, (0.0, 0.33)),))
SIGNALS = ("contact_force_N", "tangential_force_N", "normal_force_N", "stage_force_N")

#: A short slide's saved samples (``short_slides.json`` beside this file): per case its PAC/PDC codes, and per force
#: signal every ``FORCE_STRIDE``-th grid sample with the sum and sum of squares of all of them.  Pinned from the
#: code before the ring (commit 9bc8ebf and earlier) by sha256 of the raw bytes until 2026-11-23; those hashes held
#: on the machine that pinned them and on CI but not on another x86-64 (an AMD EPYC with the same pinned packages:
#: three of the four differed at HEAD 9be69b0; the cause was not found — there, numba's generic CPU and numpy without
#: its AVX2/AVX-512 paths give the same samples to the bit), so the samples are saved instead and compared within
#: rounding.  The reference profile's ridges are resolved since commit 6265ec8 (its own samples,
#: re-pinned with each change of the ridge model: on 2026-11-24 by the ridges' mean share taken over the slide's own
#: track and through stick phases, which moved that slide's codes by up to 1179, and later that day by the skin's
#: creep below the ridges' slip floor carrying their held crests, which moved 739 of its codes by up to 1701; the
#: other three cases kept their saved samples).
SAVED = Path(__file__).with_name("short_slides.json")
CASES = (("grating", "default"), ("grating", "fast"), ("sand", "default"), ("sand", "reference"))
FORCE_STRIDE = 97
#: codes may differ in this many samples, by one code (a value on a rounding edge; none did on the pinning machine)
CODE_FLIPS_ALLOWED = 2
#: forces agree within this fraction of the signal's range (far above rounding; a change of the model moves them far
#: more: the ridges' share of friction moved the reference slide's codes by up to 543)
FORCE_TOLERANCE = 1e-9


def _short_slide(texture) -> Slide:
    return Slide(0.1, texture, 0.8, 0.03, 0.04, approach_s=0.1, hold_s=0.2, start_position_m=0.2)


def _outputs(texture, fidelity: str, block_s: float) -> tuple[np.ndarray, list[np.ndarray]]:
    """A short slide's PAC/PDC codes at 4.4 kHz (alternating, noise on) and its force signals at every grid sample."""
    slide = _short_slide(texture)
    sensor = Sensor(stimuli=[slide], channels_read=["PAC", "PDC"], fidelity=fidelity, seed=7, block_s=block_s)
    t = np.arange(0.0, slide.end_s + 0.05, 1 / 4400.0)
    codes = sensor.sample(np.where(np.arange(t.size) % 2 == 0, PAC, PDC), t)
    forces = Sensor(stimuli=[slide], channels_read=["PAC"], fidelity=fidelity, seed=7, block_s=block_s,
                    record_signals=SIGNALS)
    grid = np.arange(int((slide.end_s + 0.05) * forces.fs)) / forces.fs
    return codes, [forces.signal(name, grid) for name in SIGNALS]


def _summary(codes: np.ndarray, signals: list[np.ndarray]) -> dict:
    """What :data:`SAVED` holds of a short slide's outputs."""
    return {"codes": codes.astype(int).tolist(),
            "signals": {name: {"samples": x[::FORCE_STRIDE].tolist(), "sum": float(x.sum()),
                               "sum_sq": float(np.square(x).sum()), "n": int(x.size)}
                        for name, x in zip(SIGNALS, signals)}}


def _problems(saved: dict, codes: np.ndarray, signals: list[np.ndarray]) -> list[str]:
    """How a short slide's outputs differ from the saved ones beyond rounding (empty: they agree)."""
    out = []
    old = np.array(saved["codes"])
    if old.shape != codes.shape:
        return [f"{codes.size} codes, saved {old.size}"]
    diff = np.abs(codes.astype(int) - old)
    if diff.max() > 1 or np.count_nonzero(diff) > CODE_FLIPS_ALLOWED:
        out.append(f"codes: {np.count_nonzero(diff)} differ, by up to {diff.max()}")
    for name, x in zip(SIGNALS, signals):
        ref = saved["signals"][name]
        if x.size != ref["n"]:
            out.append(f"{name}: {x.size} samples, saved {ref['n']}")
            continue
        samples = np.array(ref["samples"])
        scale = max(float(np.ptp(samples)), float(np.abs(samples).max()), 1e-300)
        worst = float(np.max(np.abs(x[::FORCE_STRIDE] - samples)))
        if worst > FORCE_TOLERANCE * scale:
            out.append(f"{name}: samples differ by {worst / scale:.3g} of the range")
        for key, value, bound in (("sum", float(x.sum()), scale * x.size),
                                  ("sum_sq", float(np.square(x).sum()), scale * scale * x.size)):
            if abs(value - ref[key]) > FORCE_TOLERANCE * max(abs(ref[key]), bound):
                out.append(f"{name}: {key} {value!r}, saved {ref[key]!r}")
    return out


@pytest.mark.unit
@pytest.mark.parametrize("name, fidelity", CASES)
def test_a_short_slides_samples_are_those_saved_before_the_ring(name, fidelity):
    """A short slide's tables are computed whole, as before: for blocks of 2 s and 37.1 ms its codes are the saved
    ones (at most two a code apart) and its forces agree with the saved ones within 1e-9 of their range, sample by
    sample and in sum and sum of squares over every grid sample (a change of the model moves them by far more)."""
    saved = json.loads(SAVED.read_text())[f"{name}-{fidelity}"]
    texture = {"sand": SAND, "grating": GRATING}[name]
    for block_s in (2.0, 0.0371):
        assert _problems(saved, *_outputs(texture, fidelity, block_s)) == [], block_s


def pin() -> None:
    """Write :data:`SAVED` from the present code, after a deliberate change of the sliding model (say why in the
    commit): ``.venv/bin/python -m emulator.tests.test_long_slide``."""
    textures = {"sand": SAND, "grating": GRATING}
    SAVED.write_text(json.dumps({f"{n}-{f}": _summary(*_outputs(textures[n], f, 2.0)) for n, f in CASES},
                                separators=(",", ":")) + "\n")


def _ring(monkeypatch, tile: int, ring_tiles: int = 3, margin_m: float = 0.01) -> None:
    """Hold every track longer than two tiles of ``tile`` positions as a ring (a short slide then uses the ring)."""
    monkeypatch.setattr(sliding, "TABLE_TILE", tile)
    monkeypatch.setattr(sliding, "TABLE_WHOLE_MAX", 2 * tile)
    monkeypatch.setattr(sliding, "RING_TILES", ring_tiles)
    monkeypatch.setattr(sliding, "RING_MARGIN_M", margin_m)


@pytest.mark.unit
@pytest.mark.parametrize("texture, fidelity", [(SAND, "default"), (GRATING, "default"), (SAND, "reference")])
def test_the_ring_gives_the_same_samples_for_any_ring_and_block_size_and_the_whole_tables_codes(monkeypatch, texture,
                                                                                               fidelity):
    """With 1024-position tiles (1 cm at default, 2.6 mm at reference) a 4 cm slide crosses many tiles: rings of 3 or
    5 tiles, margins of 1 cm or 2 mm, blocks of 2 s, 37.1 ms or 7 samples give the same samples to the bit, and the
    whole tables' codes; its forces differ from the whole tables' by rounding (a tile's FFT is not the whole
    track's)."""
    whole_codes, whole_forces = _outputs(texture, fidelity, 2.0)
    _ring(monkeypatch, 1024)
    codes, forces = _outputs(texture, fidelity, 2.0)
    sensor = Sensor(stimuli=[_short_slide(texture)], channels_read=["PAC"], fidelity=fidelity)
    assert sensor.sliding._contacts[0]["heights"].shape[1] == 3 * 1024  # premise: the ring holds the tables
    for ring_tiles, margin_m, block_s in ((5, 0.01, 0.0371), (3, 0.002, 7 / 8800)):
        _ring(monkeypatch, 1024, ring_tiles, margin_m)
        other_codes, other_forces = _outputs(texture, fidelity, block_s)
        assert np.array_equal(other_codes, codes)
        assert all(np.array_equal(a, b) for a, b in zip(other_forces, forces))
    assert np.array_equal(codes, whole_codes)
    for a, b in zip(forces, whole_forces):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * np.max(np.abs(b)))


@pytest.mark.unit
def test_a_ring_refilled_past_the_tracks_end_reads_what_the_whole_table_wraps_to(monkeypatch):
    """A rig's stage may run past the travel its tables were made for (or the skin back before the start): the whole
    table is then read modulo its length, and so is the ring, tile by tile (codes equal, forces to rounding)."""
    from emulator.sliding import CommandedMotion

    def run():
        motion = CommandedMotion(SAND, max_travel_m=0.01, latency_s=0.0, start_s=0.0)
        motion.move_finger(0.0, 4e-3)
        motion.move_finger(0.3, 0.0)
        motion.move_stage(0.4, 0.05, accel_m_per_s2=2.0)  # 6 cm in 1.2 s: past the 4.3 cm of its tables
        sensor = Sensor(stimuli=[motion], channels_read=["PAC"], record_signals=("tangential_force_N",), seed=2)
        t = np.arange(0.0, 1.6, 1 / 8800)
        out = sensor.signal("tangential_force_N", t), sensor.analog_trace("PAC", t[::4])
        contact = sensor.sliding._contacts[0]
        assert contact["state"][2] > contact["table_n"] * 10e-6  # premise: the finger went past the tables' end
        return out

    whole = run()
    _ring(monkeypatch, 512)
    ring = run()
    np.testing.assert_allclose(ring[0], whole[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(ring[1], whole[1], rtol=0, atol=1e-9)


CHILD = textwrap.dedent('''
    import json, sys
    import numpy as np
    from emulator.sensor import NoiseSources, Sensor
    from emulator.sliding import Slide
    from emulator.texture import Texture
    sand = Texture(901, "sand", "test", rms_height_m=60e-6, correlation_length_m=270e-6, hurst=0.8, mu_static=0.9,
                   mu_kinetic=0.6, modulus_Pa=5e9, seed=7)
    distance, velocity, parts = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
    slide = Slide(0.0, sand, 0.5, velocity, distance, approach_s=0.1, hold_s=0.1)
    sensor = Sensor(stimuli=[slide], channels_read=["PAC"], noise=NoiseSources.none(), block_s=2.0)
    first, last = slide.slide_start_s + 0.5, slide.slide_end_s - 0.2
    edges = np.linspace(first, last, parts + 1)
    power = [float(np.var(sensor.analog_trace("PAC", np.arange(a, b, 1 / 2200)))) for a, b in zip(edges, edges[1:])]
    status = open("/proc/self/status").read().splitlines()
    peak_MB = int(next(line for line in status if line.startswith("VmHWM")).split()[1]) / 1024
    print(json.dumps({"power_V2": power, "peak_MB": peak_MB}))
''')


def _child(distance_m: float, velocity: float, parts: int) -> dict:
    """Slide ``distance_m`` at ``velocity`` in a fresh process reading PAC: its PAC power (V²) in ``parts`` equal
    stretches of the steady slide and its peak resident memory (VmHWM, MB)."""
    out = subprocess.run([sys.executable, "-c", CHILD, str(distance_m), str(velocity), str(parts)], capture_output=True,
                         text=True, timeout=600, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.stability  # (a long run: about 12 s)
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads VmHWM from /proc")
def test_a_ten_minute_slide_at_10_cm_per_s_keeps_its_memory_and_its_pac_power():
    """60 m at 10 cm/s (10 minutes, the 1 m texture track wrapping 60 times), reading PAC: peak memory within
    20 % + 30 MB of a 0.3 m slide's (before the ring it held the whole 60 m of tables: 2.3 GB), and PAC power in each
    of the ten minutes within 1 % of their mean (measured: 0.02 %), no drift in energy."""
    short = _child(0.3, 0.1, 1)
    long = _child(60.0, 0.1, 10)
    assert long["peak_MB"] <= 1.2 * short["peak_MB"] + 30, (long["peak_MB"], short["peak_MB"])
    power = np.array(long["power_V2"])
    assert np.all(np.isfinite(power)) and power.min() > 0
    assert np.max(np.abs(power / power.mean() - 1)) < 0.01, power
    assert abs(power.mean() / short["power_V2"][0] - 1) < 0.05  # the same sliding as a short slide's


if __name__ == "__main__":
    pin()

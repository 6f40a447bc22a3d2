"""The electrodes feel the friction model's shear (issue 8 item 2): a sliding motion's electrode contact takes its
normal and tangential force from the sliding contact (emulator.sliding.ForceFeed, the mean over each electrode
period), not a fixed µk × the nominal load from touchdown on.  So during the hold (stage still, friction nil) the
pressed electrodes read as on a frictionless texture, the pattern shifts at slip along the shear, stick-slip shows in
the codes, the result does not depend on the block size or how the host batches its reads, and the rig's commanded
motion (its stage in either direction) does the same."""

import dataclasses

import numpy as np
import pytest

from emulator.channels import DEFAULT_FRAME_NAMES, ELECTRODE_FIRST, channel_index
from emulator.electrodes import electrode_positions_mm, surface_point_mm
from emulator.sensor import NoiseSources, Sensor
from emulator.sliding import CommandedMotion, Slide
from emulator.texture import Texture

#: every texture here sits inside the model's documented range: a slip of it into extrapolation fails the test
pytestmark = [pytest.mark.unit, pytest.mark.filterwarnings("error::emulator.stimuli.OutsideModelWarning")]

#: polished aluminium's friction (µs 1.05, µk 0.95: the library's T46), on a fine random surface
GRIPPY = Texture(906, "grippy", "test", rms_height_m=0.3e-6, correlation_length_m=50e-6, hurst=0.8, mu_static=1.05,
                 mu_kinetic=0.95, seed=11)
#: the same surface nearly frictionless: µ 0.02, a lubricated contact, the least a texture library takes (µ = 0 is
#: outside the friction model, its Stribeck curve divides by µ; and below µk ≈ 0.0065 the default 5 mm/s Stribeck
#: velocity leaves the friction element's passive range at this sensor's bristle damping, an extrapolation the
#: Sensor warns about)
SLICK = dataclasses.replace(GRIPPY, number=907, name="slick", mu_static=0.02, mu_kinetic=0.02)
#: a smooth texture whose static friction far exceeds its kinetic one: the skin sticks and snaps (stick-slip)
STICKY = Texture(905, "sticky", "test", rms_height_m=0.0, correlation_length_m=100e-6, hurst=0.8, mu_static=1.2,
                 mu_kinetic=0.5, seed=9)

_PAD = surface_point_mm(-5.0, 0.0)  # where a sliding motion presses (the ventral pad)
_ORDER = np.argsort(np.linalg.norm(electrode_positions_mm() - _PAD, axis=1))
PRESSED = int(_ORDER[0]) + 1  # E17, 2.2 mm ahead of the pad's centre (+x, toward the tip)
BEHIND = next(int(k) + 1 for k in _ORDER if electrode_positions_mm()[k, 0] < _PAD[0])  # E3, 1.2 mm behind it
NEAR = [int(k) + 1 for k in _ORDER[:6]]


def _index(number: int) -> int:
    return ELECTRODE_FIRST + number - 1


def _codes(sensor: Sensor, number: int, times) -> np.ndarray:
    """One electrode's codes at increasing ``times`` (s), asked for one instant at a time."""
    return np.array([float(sensor.sample([_index(number)], [t])[0]) for t in times])


def _slide(texture, velocity=0.02, force=1.0, distance=0.03):
    return Slide(0.2, texture, force, velocity, distance, approach_s=0.2, hold_s=0.5)


def test_during_the_hold_the_pressed_electrodes_read_as_on_a_frictionless_texture():
    """The stage holds still: the friction model's tangential force is zero, so the electrodes under the pad read as
    with µ 0.02 (before the fix they read µk × the load from touchdown on: 133 codes apart on polished aluminium)."""
    readings = []
    for texture in (GRIPPY, SLICK):
        slide = _slide(texture)
        sensor = Sensor(stimuli=[slide], channels_read=[f"E{n}" for n in NEAR], noise=NoiseSources.none())
        hold = np.linspace(slide.start_s + slide.approach_s + 0.05, slide.slide_start_s - 0.01, 5)
        channels = [_index(n) for n in NEAR]
        readings.append(np.array([sensor.sample(channels, np.full(len(NEAR), t)) for t in hold], float).T)
    pressed_change = readings[1][0] - 2902  # the pressed electrode does feel the press (resting code ~2902)
    assert np.all(pressed_change < -80), pressed_change
    assert np.max(np.abs(readings[0] - readings[1])) <= 1  # quantization only


def test_the_pattern_shifts_at_slip_along_the_shear_and_follows_the_friction_force():
    """At slip onset the friction force rises from zero and the dent moves along it (+x, with the stage): the
    pressed electrode ahead of the centre thins (its code falls), the one behind recovers (its code rises), by
    amounts that follow the friction force the sliding contact computes, while a nearly frictionless texture (µ 0.02
    against 0.95) moves it by a small fraction of that."""
    slide = _slide(GRIPPY)
    sensor = Sensor(stimuli=[slide], channels_read=[f"E{PRESSED}", f"E{BEHIND}", "PDC"], noise=NoiseSources.none(),
                    record_signals=("tangential_force_N",))
    start = slide.slide_start_s
    times = np.arange(start - 0.2, start + 0.6, 0.01)
    ahead, behind, shear = [], [], []
    for t in times:
        codes = sensor.sample([_index(PRESSED), _index(BEHIND)], [t, t])
        ahead.append(float(codes[0]))
        behind.append(float(codes[1]))
        shear.append(float(sensor.signal("tangential_force_N", [t])[0]))
    ahead, behind, shear = np.array(ahead), np.array(behind), np.array(shear)
    hold, sliding = times < start, times > start + 0.3
    assert np.ptp(ahead[hold]) <= 2 and np.ptp(behind[hold]) <= 2  # nothing moves while the stage holds still
    assert np.mean(shear[sliding]) > 0.8  # premise: friction ~µk·N along +x
    assert np.mean(ahead[sliding]) < np.mean(ahead[hold]) - 60
    assert np.mean(behind[sliding]) > np.mean(behind[hold]) + 5
    spread = behind - ahead  # grows with the shear along +x
    assert np.corrcoef(spread, shear)[0, 1] > 0.9
    slick = Sensor(stimuli=[_slide(SLICK)], channels_read=[f"E{PRESSED}"], noise=NoiseSources.none())
    lubricated = _codes(slick, PRESSED, times)
    shift = np.mean(ahead[sliding]) - np.mean(ahead[hold])
    assert abs(np.mean(lubricated[sliding]) - np.mean(lubricated[hold])) < 0.1 * abs(shift)  # the slide alone: little


def test_stick_slip_shows_in_the_electrode_codes():
    """On a texture whose static friction far exceeds its kinetic one the skin sticks and snaps: the tangential force
    saws up and down by about 1 N, and the electrode under the pad follows it (before the fix its code stayed
    constant while sliding, µk × the scripted load)."""
    slide = _slide(STICKY, velocity=0.002, distance=0.003)
    sensor = Sensor(stimuli=[slide], channels_read=[f"E{PRESSED}", "PDC"], noise=NoiseSources.none(),
                    record_signals=("tangential_force_N",))
    times = np.arange(slide.slide_start_s + 0.5, slide.slide_end_s - 0.1, 0.01)
    codes, shear = [], []
    for t in times:  # (the shear over the last 4 ms: the electrodes' 100 Hz low-pass)
        shear.append(float(np.mean(sensor.signal("tangential_force_N", t - np.arange(0.0, 0.004, 1 / 8800)[::-1]))))
        codes.append(float(sensor.sample([_index(PRESSED)], [t])[0]))
    codes, shear = np.array(codes), np.array(shear)
    assert np.ptp(shear) > 0.6  # premise: stick-slip
    assert np.ptp(codes) > 40 and np.std(codes) > 10
    assert np.corrcoef(codes, shear)[0, 1] < -0.8  # more shear toward the pressed electrode: a thinner gap


def _read(sensor: Sensor, channels, times, batch: int) -> np.ndarray:
    """Codes of ``channels`` (cycled) at ``times`` read ``batch`` instants at a time, as a host reads frames."""
    channels = np.resize(np.asarray(channels, dtype=np.int64), times.size)
    return np.concatenate([sensor.sample(channels[i:i + batch], times[i:i + batch])
                           for i in range(0, times.size, batch)])


@pytest.mark.parametrize("read", [("PAC", "PDC", "E17", "E3", "E13"), ("E17", "E3")])
def test_a_sliding_run_reading_electrodes_gives_the_same_codes_for_any_block_size(read):
    """Noise on, the friction's fluctuation on: every code the same for blocks of 1 sample to 2 s and for reads of
    one instant or many at a time (also when only electrodes are read: the grid then runs for their feed alone), and
    the electrodes do follow the friction: they move at slip (before the fix they did not)."""
    slide = Slide(0.05, STICKY, 0.8, 0.01, 0.004, approach_s=0.05, hold_s=0.1, lift_s=0.05)
    times = np.arange(0.0, slide.end_s + 0.05, 1 / 4400)
    channels = [channel_index(c) for c in read]
    ref = _read(Sensor(stimuli=[slide], channels_read=read, seed=4, block_s=2.0), channels, times, 4400)
    for block_s, batch in ((1 / 8800, 44), (7 / 8800, 1), (0.0123, 440), (0.37, 37)):
        got = _read(Sensor(stimuli=[slide], channels_read=read, seed=4, block_s=block_s), channels, times, batch)
        assert np.array_equal(got, ref), (block_s, batch)
    pressed = ref[np.resize(np.asarray(channels), times.size) == _index(PRESSED)]
    t_pressed = times[np.resize(np.asarray(channels), times.size) == _index(PRESSED)]
    hold = (t_pressed > slide.start_s + slide.approach_s + 0.02) & (t_pressed < slide.slide_start_s)
    sliding = (t_pressed > slide.slide_start_s + 0.1) & (t_pressed < slide.slide_end_s)
    assert np.mean(pressed[sliding]) < np.mean(pressed[hold]) - 20


def _rig_run(texture, stage_velocity):
    """A rig's commanded motion: lower at 2 mm/s from 0.07 s to 0.8 s (~1.3 mm into the skin, ~0.8 N), hold, the
    stage from 1.2 s at
    ``stage_velocity``, commands given as the host reads (each a latency ahead of what was read); the pressed and the
    behind electrode's codes every 10 ms."""
    motion = CommandedMotion(texture, latency_s=0.02, start_s=0.0, depth_m=-2e-4)
    sensor = Sensor(stimuli=[motion], channels_read=[f"E{PRESSED}", f"E{BEHIND}"], noise=NoiseSources.none())
    codes = {}
    schedule = [(0.05, lambda t: motion.move_finger(t, 2e-3)), (0.78, lambda t: motion.move_finger(t, 0.0)),
                (1.18, lambda t: motion.move_stage(t, stage_velocity, 1.0))]
    for t in np.arange(0.01, 1.8, 0.01):
        for when, command in list(schedule):
            if t >= when:
                command(t)  # given right after the last read: nothing beyond was computed
                schedule.remove((when, command))
        frame = sensor.sample([_index(PRESSED), _index(BEHIND)], [t, t]).astype(float)
        codes[round(t, 2)] = frame
    return codes


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_the_rigs_commanded_finger_holds_without_shear_and_shears_with_its_stage_either_way(direction):
    """The rig's position-controlled finger, its commands given as the host reads: during the hold the electrodes read
    as on a frictionless texture (before the fix: µk × the commanded load from touchdown on), and once the stage moves
    the pattern shifts with it — toward the tip for +x, toward the base for −x (before the fix always +x)."""
    gripping, slick = _rig_run(GRIPPY, 0.02 * direction), _rig_run(SLICK, 0.02 * direction)
    hold = [t for t in gripping if 0.9 <= t <= 1.18]
    sliding = [t for t in gripping if t >= 1.5]
    for t in hold:
        assert np.max(np.abs(gripping[t] - slick[t])) <= 1, t
    pressed_change = np.mean([gripping[t][0] - slick[t][0] for t in sliding])
    behind_change = np.mean([gripping[t][1] - slick[t][1] for t in sliding])
    assert abs(pressed_change) > 40
    assert np.sign(pressed_change) == -direction  # sheared toward the tip: the pressed electrode (ahead) thins
    assert np.sign(behind_change) == direction


def test_a_rigs_full_frame_reads_the_sliding_forces_without_computing_ahead():
    """The rig's full 44-slot frame (PAC, PDC, TDC, TAC, electrodes): a finger command given right after a read is
    accepted (the electrodes' feed made the grid run no further than the next electrode period, within the
    latency), and the pressed electrode feels the stage's shear."""
    motion = CommandedMotion(GRIPPY, latency_s=0.02, start_s=0.0, depth_m=-2e-4)
    sensor = Sensor(stimuli=[motion], channels_read=DEFAULT_FRAME_NAMES, noise=NoiseSources.none(), block_s=0.01)
    frame = np.array([channel_index(c) for c in DEFAULT_FRAME_NAMES])
    pressed_at = np.flatnonzero(frame == _index(PRESSED))[0]
    slot = 1 / 4400.0
    readings = []
    motion.move_finger(0.0, 2e-3)
    for k in range(160):  # 10 ms frames
        t = k * 0.01 + np.arange(frame.size) * slot
        readings.append(float(sensor.sample(frame, t)[pressed_at]))
        if k == 60:
            motion.move_finger(t[-1], 0.0)
        if k == 100:
            motion.move_stage(t[-1], 0.02, 1.0)
    readings = np.array(readings)
    assert np.mean(readings[140:]) < np.mean(readings[85:100]) - 40  # sheared toward the tip once the stage moves


def test_the_force_feed_is_the_mean_over_each_electrode_period_however_the_grid_is_cut():
    """The feed's value at t_k is the mean of the grid samples with instants in [t_{k−1}, t_k) (8.8 kHz grid, 500 Hz
    electrodes: 17 or 18 samples a period), the same to the bit for any cut of the grid into blocks; periods far
    outside the motion's span are not kept (they read zero)."""
    from emulator.sliding import ForceFeed

    fs, rate = 8800.0, 500.0
    rng = np.random.default_rng(5)
    normal, tangential = rng.normal(1.0, 0.1, 8800), rng.normal(0.0, 0.3, 8800)
    j = np.arange(8800)
    t_k = np.arange(1, 500) / rate
    expected = [normal[(j / fs >= t - 1 / rate) & (j / fs < t - 1e-12)].mean() for t in t_k[:20]]
    values = []
    for cuts in ([8800], [1] * 100 + [8700], list(rng.integers(1, 300, 100))):
        feed = ForceFeed(rate, fs, 0.0, np.inf)
        n0 = 0
        for n in cuts:
            n = min(n, 8800 - n0)
            if n > 0:
                feed.push(n0, n, normal[n0:n0 + n], tangential[n0:n0 + n])
            n0 += n
        if n0 < 8800:
            feed.push(n0, 8800 - n0, normal[n0:], tangential[n0:])
        assert feed.last_grid_index(t_k[-1]) == 8782  # period 499 ends before grid sample ⌈499 × 17.6⌉ = 8783
        values.append(feed(t_k))
    for got in values[1:]:
        assert np.array_equal(got[0], values[0][0]) and np.array_equal(got[1], values[0][1])
    np.testing.assert_allclose(values[0][0][:20], expected, rtol=1e-14)
    late = ForceFeed(rate, fs, 0.5, 0.6)  # a motion from 0.5 s to 0.6 s: only its periods (and one each side) kept
    late.push(0, 8800, normal, tangential)
    assert late._k[0].min() >= 0.5 * rate - 1 and late._k[0].max() <= 0.6 * rate + 1
    n, _ = late(t_k)
    assert np.all(n[t_k < 0.495] == 0.0) and np.all(n[t_k > 0.605] == 0.0) and np.all(n[(t_k > 0.5) & (t_k < 0.6)] > 0)


def test_the_electrode_model_and_the_sliding_contact_are_built_only_when_needed():
    """A sliding scene not reading electrodes builds no electrode model; one reading only electrodes runs the sliding
    contact (for their feed) and nothing of the pressure path."""
    slide = _slide(GRIPPY)
    assert Sensor(stimuli=[slide], channels_read=["PAC"]).electrodes is None
    only = Sensor(stimuli=[slide], channels_read=[f"E{PRESSED}"])
    assert [e.name for e in only.graph.effects] == ["sliding_contact"]

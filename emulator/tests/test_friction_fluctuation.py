"""The friction coefficient's fluctuation with slip distance (emulator.texture.friction_fluctuation, read in
emulator.friction.slide_block): its spectrum and RMS as designed, that the friction force carries it while the
skin slides, that it does nothing while the skin sticks, and that it is deterministic and block-size independent."""

import dataclasses

import numpy as np
import pytest

from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.sliding import Slide, fluctuation_table
from emulator.texture import (FRICTION_FLUCTUATION_BAND_M, FRICTION_FLUCTUATION_RMS, SURFACE_LENGTH_M, Texture,
                              friction_fluctuation)

FLAT = Texture(903, "flat", "test", rms_height_m=0.0, correlation_length_m=100e-6, hurst=0.8, mu_static=1.0,
               mu_kinetic=0.8, seed=9)
OFF = dataclasses.replace(FLAT, friction_fluctuation_rms=0.0)
GRID_HZ = 8800.0  # the default profile's grid


def _tangential(texture, force_N, velocity, distance, block_s=2.0, approach_s=0.1, hold_s=0.2):
    slide = Slide(0.1, texture, force_N, velocity, distance, approach_s=approach_s, hold_s=hold_s, accel_s=0.01)
    s = Sensor(stimuli=[slide], channels_read=["PDC"], noise=NoiseSources.none(), block_s=block_s,
               record_signals=("tangential_force_N",), seed=3)
    t = np.arange(0.0, slide.end_s, 1 / GRID_HZ)
    return slide, t, s.signal("tangential_force_N", t)


@pytest.mark.unit
@pytest.mark.parametrize("dx_m", [2.5e-6, 10e-6])
def test_fluctuation_spectrum_is_one_over_q_inside_its_band_and_nothing_outside(dx_m):
    """Power ∝ 1/q (k·|FFT|² constant to 1e-9) over 20 µm – 10 mm wavelengths, zero elsewhere."""
    eps = friction_fluctuation(FLAT, dx_m)
    power = np.abs(np.fft.rfft(eps)) ** 2
    k = np.arange(power.size)
    finest, coarsest = FRICTION_FLUCTUATION_BAND_M
    band = (k >= SURFACE_LENGTH_M / coarsest) & (k <= SURFACE_LENGTH_M / finest) & (k < eps.size / 2)
    flat = power[band] * k[band]
    assert np.ptp(flat) < 1e-9 * flat.mean()
    assert power[~band].max() < 1e-20 * power[band].max()


@pytest.mark.unit
def test_fluctuation_rms_is_the_textures_and_the_same_surface_at_any_resolution():
    fine, default = friction_fluctuation(FLAT, 2.5e-6), friction_fluctuation(FLAT, 10e-6)
    assert np.std(fine) == pytest.approx(FRICTION_FLUCTUATION_RMS, rel=1e-6)
    assert np.std(default) == pytest.approx(FRICTION_FLUCTUATION_RMS, rel=1e-3)  # (its Nyquist bin is dropped)
    np.testing.assert_allclose(fine[::4], default, atol=1e-3 * FRICTION_FLUCTUATION_RMS)
    assert np.mean(default) == pytest.approx(0.0, abs=1e-12)
    half = dataclasses.replace(FLAT, friction_fluctuation_rms=0.015)
    np.testing.assert_allclose(friction_fluctuation(half, 10e-6), 0.5 * default, atol=1e-15)
    assert not np.any(friction_fluctuation(OFF, 10e-6))
    other = friction_fluctuation(dataclasses.replace(FLAT, seed=10), 10e-6)
    assert abs(np.corrcoef(default, other)[0, 1]) < 0.1  # each texture its own
    np.testing.assert_array_equal(friction_fluctuation(FLAT, 10e-6), default)  # deterministic


@pytest.mark.unit
def test_a_trials_table_is_the_textures_fluctuation_from_its_start_position():
    dx = 10e-6
    track = friction_fluctuation(FLAT, dx)
    table = fluctuation_table(FLAT, 0.3, 0.05, dx)
    np.testing.assert_array_equal(table, track[30000:30000 + table.size])
    wrapped = fluctuation_table(FLAT, SURFACE_LENGTH_M - 0.01, 0.05, dx)  # the surface repeats
    np.testing.assert_array_equal(wrapped[:1000], track[-1000:])
    np.testing.assert_array_equal(wrapped[1000:2000], track[:1000])


@pytest.mark.unit
def test_steady_sliding_friction_carries_the_fluctuation_at_the_slipped_position():
    """At 3 cm/s on a flat texture (steady sliding: no fluctuation at all without it), the tangential force follows
    µ(V)·N·(1 + ε(p)) at the slip position p = stage travel − skin deflection: relative RMS within 0.8–1.1 of the
    prediction's (the bristles smooth the finest wavelengths), correlation > 0.8."""
    p = SensorParams()
    force, v = 1.0, 0.03
    for texture in (OFF, FLAT):
        slide, t, ft = _tangential(texture, force, v, 0.04)
        sel = (t > slide.slide_start_s + 0.1) & (t < slide.slide_end_s - 0.02)
        rel = ft[sel] / ft[sel].mean() - 1
        if texture is OFF:
            assert np.std(rel) < 1e-9
    stage = np.cumsum(slide.stage_velocity_m_per_s(t)) / GRID_HZ
    position = stage - ft / p.skin_tangential_stiffness_N_per_m
    eps = friction_fluctuation(FLAT, 10e-6)
    predicted = 1 + np.interp(position[sel] / 10e-6, np.arange(eps.size), eps)
    predicted = predicted / predicted.mean() - 1
    assert 0.8 < np.std(rel) / np.std(predicted) < 1.1
    assert np.corrcoef(rel, predicted)[0, 1] > 0.8


@pytest.mark.unit
def test_nothing_fluctuates_while_the_skin_sticks():
    """During the stick ramp (the stage moving, the skin stuck) the fluctuation changes the tangential force by a
    smooth amount only: the difference on − off, less its linear trend, is below 1e-3 of the sliding fluctuation."""
    force, v = 1.0, 0.005  # the skin sticks for ~0.15 s (µs·N / (k_t·V))
    slide, t, on = _tangential(FLAT, force, v, 0.01)
    _, _, off = _tangential(OFF, force, v, 0.01)
    diff = on - off
    stick = (t > slide.slide_start_s + 0.02) & (t < slide.slide_start_s + 0.08)
    assert np.max(on[stick]) < 0.9 * FLAT.mu_static * force  # (still sticking)
    residual = diff[stick] - np.polyval(np.polyfit(t[stick], diff[stick], 1), t[stick])
    sliding = (t > slide.slide_start_s + 0.5) & (t < slide.slide_end_s - 0.02)
    assert np.std(residual) < 1e-3 * np.std(diff[sliding])
    held = (t > slide.start_s + 0.12) & (t < slide.slide_start_s)  # pressed, the stage still: no force at all
    assert not np.any(on[held]) and not np.any(off[held])


@pytest.mark.unit
def test_fluctuating_friction_does_not_depend_on_block_size():
    ref = _tangential(FLAT, 0.5, 0.03, 0.01, block_s=1.0, approach_s=0.05, hold_s=0.05)[2]
    for block_s in (1 / 8800, 7 / 8800, 0.0123):
        got = _tangential(FLAT, 0.5, 0.03, 0.01, block_s=block_s, approach_s=0.05, hold_s=0.05)[2]
        assert np.array_equal(got, ref), block_s
    assert np.all(np.isfinite(ref))


@pytest.mark.unit
def test_the_break_away_force_scales_with_the_fluctuation_where_the_skin_sticks():
    """The static coefficient fluctuates too: landing where ε averaged over 0.2 mm is largest (~+2 σ), the stick
    peak is (1 + ε) times the peak without the fluctuation (±0.02), not the same."""
    eps = np.convolve(friction_fluctuation(FLAT, 10e-6)[:20000], np.ones(20) / 20, mode="same")
    start = int(np.argmax(eps)) * 10e-6
    peaks = []
    for texture in (FLAT, OFF):
        slide = Slide(0.1, texture, 1.0, 0.005, 0.005, approach_s=0.1, hold_s=0.2, accel_s=0.001,
                      start_position_m=start)
        s = Sensor(stimuli=[slide], channels_read=["PDC"], noise=NoiseSources.none(),
                   record_signals=("tangential_force_N",), seed=3)
        peaks.append(s.signal("tangential_force_N", np.arange(0.0, slide.end_s, 1 / GRID_HZ)).max())
    assert eps.max() > 0.05
    assert peaks[0] / peaks[1] == pytest.approx(1 + eps.max(), abs=0.02)


@pytest.mark.stability
def test_an_absurd_fluctuation_stays_finite_and_bounded():
    """ε of 200 % RMS (far beyond any source) reaches below −1: the scale is held at MIN_FLUCTUATION_SCALE and the
    forces stay finite, within the largest friction µs·N·(1 + max ε) (the skin, stretched by a grippy stretch,
    may spring back past zero where the friction drops to a tenth: violent stick-slip, not a failure)."""
    wild = dataclasses.replace(FLAT, friction_fluctuation_rms=2.0)
    slide, t, ft = _tangential(wild, 1.0, 0.05, 0.02)
    assert np.all(np.isfinite(ft))
    bound = wild.mu_static * 1.0 * (1 + friction_fluctuation(wild, 10e-6).max())
    assert np.abs(ft).max() < 1.5 * bound


@pytest.mark.unit
def test_where_the_fluctuation_reaches_below_minus_one_friction_is_held_at_its_floor():
    """A table of ε = −5 everywhere: steady sliding at 5 cm/s settles at MIN_FLUCTUATION_SCALE·µk·N (+ the viscous
    term), not at a negative friction."""
    from emulator import friction

    p, n, dt = SensorParams(), 4000, 1 / GRID_HZ
    force, v = 1.0, 0.05
    out = [np.zeros(n) for _ in range(4)]
    heights = np.zeros((1, 100))
    friction.slide_block(np.full(n, force), np.full(n, v), dt, 1, heights, heights.copy(), np.array([2.5e-3]),
                         np.full(100, -5.0), 10e-6, friction.new_state(), False, p.contact_stiffness_N_per_m1_5,
                         p.contact_radius_at_1N_m, 1e9, 3e-3, p.skin_tangential_stiffness_N_per_m,
                         p.skin_tangential_damping_N_s_per_m, p.bristle_stiffness_per_N, p.bristle_damping_per_N,
                         FLAT.mu_static, FLAT.mu_kinetic, FLAT.stribeck_velocity_m_per_s, 0.0, *out)
    expected = friction.MIN_FLUCTUATION_SCALE * FLAT.mu_kinetic * force
    assert out[1][-1] == pytest.approx(expected, rel=1e-3)


@pytest.mark.unit
def test_the_slip_velocity_out_is_each_grid_steps_mean_over_its_substeps():
    """Through stick and slip (1 N, the stage from rest to 5 cm/s), with 4 substeps per grid step: the slip velocity
    reported per step times the step is exactly how far the contact slid in it (its position's step) — the mean over
    the substeps, not the last one's value (a mutation hunt)."""
    from emulator import friction

    p, n, dt = SensorParams(), 2000, 1 / GRID_HZ
    normal, tangential, slip, position = (np.zeros(n) for _ in range(4))
    heights = np.zeros((1, 100))
    stage = np.minimum(np.arange(n) * dt * 2.0, 0.05)  # accelerating at 2 m/s², then 5 cm/s: the skin sticks, slips
    friction.slide_block(np.full(n, 1.0), stage, dt, 4, heights, heights.copy(), np.array([2.5e-3]), np.zeros(100),
                         10e-6, friction.new_state(), False, p.contact_stiffness_N_per_m1_5, p.contact_radius_at_1N_m,
                         1e9, 3e-3, p.skin_tangential_stiffness_N_per_m, p.skin_tangential_damping_N_s_per_m,
                         p.bristle_stiffness_per_N, p.bristle_damping_per_N, FLAT.mu_static, FLAT.mu_kinetic,
                         FLAT.stribeck_velocity_m_per_s, 0.0, normal, tangential, slip, position)
    assert np.ptp(slip) > 0.01  # it did stick and slip
    np.testing.assert_allclose(np.diff(position), slip[1:] * dt, rtol=1e-9, atol=1e-15)

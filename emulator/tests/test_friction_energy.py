"""The LuGre friction element takes energy and never gives back more than it stores (issue: "the LuGre nominal
breaches its derived passivity bound").  Per implicit step of the sliding kernel (:func:`friction._step_velocity`,
the step the kernel takes on a flat surface: the skin a massless spring–damper between the core and the contact),
the work the slip does on the friction element, F·v_r·h, less the growth of the bristles' elastic energy
N·σ0·z²/2 at that step's load, is the energy the element dissipates: it must not be negative.  The hard cases:
creep at 0.1 mm/s (stick-slip, each slip reaching metres per second through the massless skin), 20 cm/s and
0.5 m/s at the 20 N scene limit, load steps 0.5 ↔ 20 N while sliding, with and without the texture's friction
fluctuation, on the library's textures whose µ falls most with slip (bamboo placemat, µv 0.08; faux fur, µv 0)."""

import math

import numpy as np
import pytest
from numba import njit

from emulator import friction
from emulator.params import SensorParams
from emulator.texture import FRICTION_FLUCTUATION_RMS, Texture, friction_fluctuation

pytestmark = pytest.mark.unit

#: the friction step of the reference grid (70.4 kHz × 4 substeps), s
STEP_S = 1.0 / (4400.0 * 16 * 4)
#: µ falls by a fifth to a quarter from static to kinetic (the library's extremes of (µs − µk)/µk, 0.25 and 0.175)
TEXTURES = {"bamboo placemat": Texture(115, "bamboo placemat", "test", rms_height_m=1e-6, correlation_length_m=1e-4,
                                       hurst=0.8, mu_static=0.641, mu_kinetic=0.512, mu_per_velocity_s_per_m=0.08,
                                       seed=115),
            "faux fur": Texture(117, "faux fur", "test", rms_height_m=1e-6, correlation_length_m=1e-4, hurst=0.8,
                                mu_static=0.45, mu_kinetic=0.383, seed=117)}
DX_M = 2.5e-6


@njit(cache=False)
def _dissipation(load_N, stage_m_per_s, h, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v, eps, dx):
    """Per step: the friction element's dissipation (J), its force (N) and the slip velocity (m/s)."""
    x = z = p = u_prev = 0.0
    n = stage_m_per_s.size
    out, force_out, slip_out = np.zeros(n), np.zeros(n), np.zeros(n)
    for k in range(n):
        normal, v = load_N[k], stage_m_per_s[k]
        scale = 1.0
        if eps.size > 1:  # µ scaled by 1 + ε(position), as the kernel reads its fluctuation table
            at = p / dx
            i = int(math.floor(at))
            f = at - i
            scale = max(1.0 + eps[i % eps.size] * (1.0 - f) + eps[(i + 1) % eps.size] * f, 0.1)
        u, znew, force = friction._step_velocity(u_prev, x, z, v, h, normal, k_t, c_t, sigma0, sigma1,
                                                 mu_s * scale, mu_k * scale, vs, mu_v)
        vr = v - u
        out[k] = force * vr * h - normal * sigma0 * (znew * znew - z * z) / 2.0
        force_out[k], slip_out[k] = force, vr
        x += u * h
        z = znew
        p += vr * h
        u_prev = u
    return out, force_out, slip_out


def _stage(v_m_per_s: float, duration_s: float) -> np.ndarray:
    """The stage's velocity (m/s) per step: 1 ms ramps, moving from 10 ms to 50 ms before the end."""
    t = np.arange(int(duration_s / STEP_S)) * STEP_S
    return v_m_per_s * np.clip((t - 0.01) / 1e-3, 0, 1) * np.clip((duration_s - 0.05 - t) / 1e-3, 0, 1)


#: (name, load N per step, stage m/s per step)
CASES = {"creep 0.1 mm/s, 5 N": lambda: (5.0, _stage(1e-4, 12.0)),
         "20 cm/s, 20 N": lambda: (20.0, _stage(0.2, 0.3)),
         "0.5 m/s, 20 N": lambda: (20.0, _stage(0.5, 0.3)),
         "1 cm/s, 2 N": lambda: (2.0, _stage(0.01, 1.0)),
         "load steps 0.5 <-> 20 N every 20 ms at 5 cm/s": lambda: (None, _stage(0.05, 0.3))}


@pytest.mark.parametrize("fluctuation", [False, True], ids=["flat", "fluctuating"])
@pytest.mark.parametrize("texture", TEXTURES)
@pytest.mark.parametrize("case", CASES)
def test_the_friction_element_dissipates_at_every_step(case, texture, fluctuation):
    """At the nominal σ0, σ1, skin stiffness and damping, no step gives back energy beyond rounding (1e-12 of the
    case's dissipation), and under a steady load the friction force never pushes the skin along a slip faster
    than 10 Stribeck velocities (it did, by 7.7 N at 20 N and 20 cm/s, with 1.4e-4 J given back in one step: at a
    slip's onset the constant bristle damping's term σ1·dz/dt outweighed the bristles' force; a load step may
    push, with the bristles' energy the load put in)."""
    p, tex = SensorParams(), TEXTURES[texture]
    load, stage = CASES[case]()
    steady = load is not None
    if not steady:
        t = np.arange(stage.size) * STEP_S
        load = np.where((t // 0.02) % 2 == 0, 0.5, 20.0)
    else:
        load = np.full(stage.size, load)
    eps = friction_fluctuation(tex, DX_M) if fluctuation else np.zeros(1)
    dissipated, force, slip = _dissipation(load, stage, STEP_S, p.skin_tangential_stiffness_N_per_m,
                                           p.skin_tangential_damping_N_s_per_m, p.bristle_stiffness_per_N,
                                           p.bristle_damping_per_N, tex.mu_static, tex.mu_kinetic,
                                           tex.stribeck_velocity_m_per_s, tex.mu_per_velocity_s_per_m, eps, DX_M)
    total = dissipated.sum()
    assert total > 0.0
    worst = int(np.argmin(dissipated))
    assert dissipated[worst] >= -1e-12 * total, (dissipated[worst], total, force[worst], slip[worst])
    fast = np.abs(slip) > 10 * tex.stribeck_velocity_m_per_s
    assert not steady or np.all(force[fast] * np.sign(slip[fast]) > 0.0)


def test_a_stribeck_velocity_past_its_limit_gives_energy_back_and_one_at_it_does_not():
    """The fading damping keeps the element passive only while σ1·v_s/√(2e) ≤ 4·g: a texture the library's ranges
    alone took (µs 0.3, µk 0.2, v_s 500 mm/s, 0.01–1000 allowed) under the largest σ1 a sensor may have (30 s/m)
    gives energy back at a slip's onset (5 N, the stage ramped to 0.1–0.5 m/s in 0.3 ms, 14 µs steps); at
    :func:`friction.stribeck_velocity_limit_m_per_s` (51 mm/s for it, what the library now allows) no step does,
    with or without the fluctuation."""
    from emulator.params import PARAMETER_FIELDS

    sigma1 = PARAMETER_FIELDS["bristle_damping_per_N"].metadata["range"][1]
    p = SensorParams(bristle_damping_per_N=sigma1)
    h = 4 * STEP_S
    t = np.arange(int(0.1 / h)) * h
    limit = friction.stribeck_velocity_limit_m_per_s(0.2, sigma1, FRICTION_FLUCTUATION_RMS)
    assert limit == pytest.approx(0.051, rel=0.01)

    def worst(vs, speed, fluctuation):
        tex = Texture(950, "slick", "test", rms_height_m=1e-6, correlation_length_m=1e-4, hurst=0.8, mu_static=0.3,
                      mu_kinetic=0.2, stribeck_velocity_m_per_s=vs, seed=950)
        eps = friction_fluctuation(tex, DX_M) if fluctuation else np.zeros(1)
        d, _, _ = _dissipation(np.full(t.size, 5.0), speed * np.clip((t - 0.01) / 3e-4, 0, 1), h,
                               p.skin_tangential_stiffness_N_per_m, p.skin_tangential_damping_N_s_per_m,
                               p.bristle_stiffness_per_N, sigma1, tex.mu_static, tex.mu_kinetic, vs, 0.0, eps, DX_M)
        return d.min() / d.sum()

    assert min(worst(0.5, v, False) for v in (0.1, 0.25, 0.5)) < -1e-6
    for v in (0.1, 0.25, 0.5):
        for fluctuation in (False, True):
            assert worst(limit, v, fluctuation) >= -1e-12, (v, fluctuation)


def test_a_python_slide_on_a_texture_past_its_stribeck_limit_is_warned_of_at_the_sensors_own_damping():
    """A Texture made in Python skips the library's check: a Sensor warns (OutsideModelWarning naming the slide,
    texture, field, value and limit) when its Stribeck velocity passes the limit at the sensor's own σ1 — 0.5 m/s
    at µk 0.2 and the nominal 10 s/m (limit 0.153 m/s) — and takes 0.1 m/s, and 0.5 m/s without bristle damping."""
    import warnings

    from emulator.sensor import Sensor
    from emulator.sliding import Slide
    from emulator.stimuli import OutsideModelWarning

    def slide(vs):
        tex = Texture(950, "slick", "test", rms_height_m=1e-6, correlation_length_m=1e-4, hurst=0.8, mu_static=0.3,
                      mu_kinetic=0.2, stribeck_velocity_m_per_s=vs, seed=950)
        return Slide(0.1, tex, 0.5, 0.01, 0.01)

    with pytest.warns(OutsideModelWarning, match=r"Slide at 0\.1 s: texture 950 \(slick\): stribeck_velocity_m_per_s "
                                                 r"= 0\.5 is past 0\.153 m/s, .* bristle_damping_per_N = 10 s/m"):
        Sensor(stimuli=[slide(0.5)], channels_read=["PDC"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Sensor(stimuli=[slide(0.1)], channels_read=["PDC"])
        Sensor(stimuli=[slide(0.5)], channels_read=["PDC"], params=SensorParams(bristle_damping_per_N=0.0))

"""Texture surfaces as data, and the height profile a finger sliding in a straight line sees on them.

A :class:`Texture` is a random self-affine surface (RMS height, correlation length, roughness exponent) plus
optional periodic components (gratings, weaves, meshes, hooks), friction (static, kinetic, velocity dependence),
compliance (the surface material's Young's modulus) and a thermal material for :mod:`emulator.thermal`.

The random component's one-sided spatial power spectrum is flat below ``q0 = 2π / correlation_length`` and falls
as ``q^-(1 + 2H)`` above it (the 1-D section of an isotropic self-affine surface with Hurst exponent ``H``), up
to the track's resolution.  A track is generated deterministically from the texture's own ``seed``: the same
texture is the same surface in every trial; a trial only starts somewhere else on it (``start_m``).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

#: Length of the stored surface (m): one period of the generated random component; tracks wrap around it.
SURFACE_LENGTH_M = 1.0

#: Relative RMS of the friction coefficient's fluctuation with slip distance (δµ/µ) over
#: :data:`FRICTION_FLUCTUATION_BAND_M`, for every texture.  Literature: a finger pad sliding steadily on smooth
#: glass varies its friction coefficient by less than ±10 % about the mean (stick-slip phases: more than ±25 %;
#: Derler et al., Wear 2013, "Stick-slip phenomena in the friction of human skin"); for a trace whose peaks reach
#: ~3 σ that is an RMS of ~3 %, taken here (plausible range 1–5 %; chosen before any claim was looked at).
FRICTION_FLUCTUATION_RMS = 0.03
#: Wavelengths (m) of the friction fluctuation along the slip, finest to coarsest: power ∝ 1/q in between (a
#: finger's friction force on a smooth flat surface has a 1/f background, Wiertlewski, Hudin & Hayward, IEEE
#: World Haptics 2011; a 1/f friction force is also what Xu, Zhou & Persson, Soft Matter 2025, find consistent
#: with sliding blocks' displacement noise ∝ ω^-5).  Model choices: 10 mm, about the contact's diameter (longer
#: drifts are traction, not vibration); 20 µm, below the LuGre pre-sliding corner 2π·µ/σ0 ≈ 60 µm that
#: smooths finer changes anyway, and resolved by the default and reference profiles' 10 and 2.5 µm tracks.
FRICTION_FLUCTUATION_BAND_M = (20e-6, 10e-3)


@dataclass(frozen=True)
class PeriodicComponent:
    """A periodic relief: ridges of ``period_m`` with fundamental amplitude ``amplitude_m`` (peak, m).

    ``harmonics`` are the relative amplitudes of the 2nd, 3rd, … harmonics (a square-ish grating has 0, 1/3, …
    on odd ones); ``orientation_deg`` is the angle between the sliding direction and the ridges' normal, so a
    finger sliding across the ridges (0°) meets them at ``period_m`` and at 60° every 2 × ``period_m``.
    """

    period_m: float
    amplitude_m: float
    harmonics: tuple[float, ...] = ()
    orientation_deg: float = 0.0

    @property
    def track_period_m(self) -> float:
        """Period along the sliding direction (m)."""
        c = abs(math.cos(math.radians(self.orientation_deg)))
        return self.period_m / max(c, 1e-3)


@dataclass(frozen=True)
class Texture:
    """One texture of the library (SI units). ``source`` says where its numbers come from."""

    number: int
    name: str
    group: str
    rms_height_m: float
    correlation_length_m: float
    hurst: float
    mu_static: float
    mu_kinetic: float
    stribeck_velocity_m_per_s: float = 0.005
    mu_per_velocity_s_per_m: float = 0.0
    modulus_Pa: float = 1e9
    material: str = "acrylic"
    periodic: tuple[PeriodicComponent, ...] = ()
    seed: int = 0
    source: str = ""
    description: str = ""
    #: relative RMS of the friction fluctuation (δµ/µ; override only with a sourced reason, 0 switches it off)
    friction_fluctuation_rms: float = FRICTION_FLUCTUATION_RMS

    def __post_init__(self):
        """Refuse what the friction model cannot take (its Stribeck curve divides by µ and by the Stribeck velocity),
        naming the texture, field and value; the library's own ranges are narrower (bench/textures/library.py)."""
        for name in ("mu_static", "mu_kinetic", "stribeck_velocity_m_per_s"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"texture {self.number} ({self.name}): {name} = {value!r} must be a finite number > 0")
        if self.mu_kinetic > self.mu_static:
            raise ValueError(f"texture {self.number} ({self.name}): mu_kinetic = {self.mu_kinetic!r} must not exceed "
                             f"mu_static = {self.mu_static!r}")

    def friction_coefficient(self, v_m_per_s):
        """Steady-sliding friction coefficient at relative speed ``v`` (m/s): Stribeck curve plus a viscous rise."""
        v = np.abs(np.asarray(v_m_per_s, float))
        return (self.mu_kinetic + (self.mu_static - self.mu_kinetic) * np.exp(-(v / self.stribeck_velocity_m_per_s) ** 2)
                + self.mu_per_velocity_s_per_m * v)


@dataclass
class SurfaceTrack:
    """Heights (m) of a texture along the sliding direction on a uniform grid of ``dx_m``, from ``start_m``."""

    heights_m: np.ndarray
    dx_m: float
    start_m: float = 0.0
    extra: dict = field(default_factory=dict)

    def at(self, x_m) -> np.ndarray:
        """Height (m) at positions ``x_m`` along the track, linearly interpolated (positions wrap)."""
        u = (np.asarray(x_m, float) - self.start_m) / self.dx_m
        n = self.heights_m.size
        i = np.floor(u).astype(np.int64)
        f = u - i
        i %= n
        return self.heights_m[i] * (1 - f) + self.heights_m[(i + 1) % n] * f


def random_profile(texture: Texture, dx_m: float, length_m: float = SURFACE_LENGTH_M) -> np.ndarray:
    """The texture's random self-affine component over ``length_m`` at spacing ``dx_m`` (m; periodic, zero
    mean, RMS = ``rms_height_m``). Deterministic from ``texture.seed``: the same surface at any ``dx_m``
    (components with wavelength below 2·dx are absent)."""
    n = int(round(length_m / dx_m))
    if texture.rms_height_m <= 0 or n < 4:
        return np.zeros(max(n, 1))
    # the spectrum's phases and amplitudes are drawn on a fixed frequency list, so refining dx only adds
    # finer components and never changes the coarser ones
    rng = np.random.default_rng(np.random.SeedSequence([texture.seed, 0x5EED]))
    k = np.arange(1, n // 2 + 1)
    psd = _self_affine_psd(texture, 2 * np.pi * k / length_m)
    n_max = int(round(length_m / 0.5e-6)) // 2  # the finest resolution ever used: 0.5 µm
    phases = _stable_draws(rng, n_max, k.size)
    # scale so that the RMS over the band resolved at the reference spacing is the texture's RMS height
    full = float(np.sqrt(np.sum(_reference_psd(texture, length_m))))
    resolved = float(np.sqrt(np.sum(psd)))
    return _spectral_track(n, k, np.sqrt(psd), phases, texture.rms_height_m) * (resolved / full)


def _self_affine_psd(texture: Texture, q: np.ndarray) -> np.ndarray:
    """The random component's one-sided power spectrum (relative) at wavenumbers ``q`` (rad/m): flat below
    2π / correlation length, ∝ q^-(1 + 2H) above."""
    q0 = 2 * np.pi / texture.correlation_length_m
    return np.where(q < q0, 1.0, (q / q0) ** -(1 + 2 * texture.hurst))


def _reference_psd(texture: Texture, length_m: float, dx_ref_m: float = 0.5e-6) -> np.ndarray:
    k = np.arange(1, int(round(length_m / dx_ref_m)) // 2 + 1)
    return _self_affine_psd(texture, 2 * np.pi * k / length_m)


def _spectral_track(n: int, k: np.ndarray, amplitude: np.ndarray, phases: np.ndarray, rms: float,
                    band_power: float | None = None) -> np.ndarray:
    """A periodic track of ``n`` samples from a one-sided spectrum: cosines of relative ``amplitude`` and
    ``phases`` (turns) at the wavenumbers ``k`` (cycles per track, at most n/2), scaled to the RMS ``rms``
    (the track's unit) by one of two rules: the track's own RMS (``band_power`` None), or that of a whole band
    whose amplitudes have the total power ``band_power`` = Σ A² (a bin of amplitude A is a cosine of variance
    2·A²/n²), so a track lacking some of the band's bins has less."""
    spectrum = np.zeros(n // 2 + 1, complex)
    spectrum[k] = amplitude * np.exp(2j * np.pi * phases)
    track = np.fft.irfft(spectrum, n)
    if band_power is None:
        return track / float(np.sqrt(np.mean(track**2))) * rms
    return track * (rms * n / math.sqrt(2.0 * band_power))


def _stable_draws(rng: np.random.Generator, n_total: int, n_used: int) -> np.ndarray:
    """The first ``n_used`` of ``n_total`` uniform draws, identical whatever ``n_used`` is."""
    return rng.random(n_total)[:n_used]


def friction_fluctuation(texture: Texture, dx_m: float, length_m: float = SURFACE_LENGTH_M) -> np.ndarray:
    """Relative fluctuation ε (1) of the friction coefficient along the texture (µ → µ·(1 + ε)), every ``dx_m``
    over ``length_m`` (m; periodic, zero mean): power ∝ 1/q over the wavelengths of
    :data:`FRICTION_FLUCTUATION_BAND_M`, RMS ``texture.friction_fluctuation_rms`` over that whole band (a track too
    coarse to resolve its finest wavelengths lacks them).  Deterministic from ``texture.seed`` and the same at any
    ``dx_m``: components are drawn on a fixed frequency list, as for :func:`random_profile`."""
    n = int(round(length_m / dx_m))
    if texture.friction_fluctuation_rms <= 0 or n < 4:
        return np.zeros(max(n, 1))
    finest, coarsest = FRICTION_FLUCTUATION_BAND_M
    k = np.arange(max(1, math.ceil(length_m / coarsest)), math.floor(length_m / finest) + 1)
    rng = np.random.default_rng(np.random.SeedSequence([texture.seed, 0xF1C7]))
    phases = rng.random(k.size)
    amplitude = 1.0 / np.sqrt(k)  # power ∝ 1/q
    keep = k < n / 2  # below the track's Nyquist wavenumber
    # normalised to the whole band's variance
    return _spectral_track(n, k[keep], amplitude[keep], phases[keep], texture.friction_fluctuation_rms,
                           float(np.sum(amplitude**2)))


def periodic_profile(texture: Texture, x_m: np.ndarray) -> np.ndarray:
    """Sum of the texture's periodic components at positions ``x_m`` (m)."""
    x = np.asarray(x_m, float)
    out = np.zeros_like(x)
    for k, amplitude in zip(*_harmonics(texture)):
        out += amplitude * np.cos(k * x)
    return out


def _harmonics(texture: Texture) -> tuple[list[float], list[float]]:
    """Wavenumbers (rad/m) and amplitudes (m) of every periodic component's harmonics, fundamental first; a zero
    harmonic (a square wave's even ones) adds exactly nothing and is left out."""
    k, amp = [], []
    for c in texture.periodic:
        w = 2 * np.pi / c.track_period_m
        for j, rel in enumerate((1.0, *c.harmonics), start=1):
            if rel:
                k.append(j * w)
                amp.append(rel * c.amplitude_m)
    return k, amp


def periodic_on_grid(texture: Texture, x0_m: float, dx_m: float, n: int) -> np.ndarray:
    """:func:`periodic_profile` at the ``n`` positions ``x0_m + i·dx_m`` (m), by angle addition: each harmonic
    ``A·cos(k·(x0 + i·dx)) = A·cos(k·x0)·cos(k·i·dx) − A·sin(k·x0)·sin(k·i·dx)``, the tables of cos and sin of
    ``k·i·dx`` kept per texture and spacing (a trial then costs no cosine per sample).  The same values to
    rounding (~1e-15 of the amplitude; test_texture_tracks)."""
    if not texture.periodic:
        return np.zeros(n)
    wavenumbers, amplitudes, cos_table, sin_table = _harmonic_tables(texture, dx_m, n)
    phase = wavenumbers * x0_m
    return (amplitudes * np.cos(phase)) @ cos_table[:, :n] - (amplitudes * np.sin(phase)) @ sin_table[:, :n]


def _harmonic_tables(texture: Texture, dx_m: float, n: int) -> tuple:
    """(wavenumbers rad/m, amplitudes m, cos table, sin table) of the texture's periodic harmonics (zero ones left
    out), the tables (harmonic × position) of ``cos``/``sin(k·i·dx)`` for at least ``n`` positions."""
    n_table = 1 << max(10, (int(n) - 1).bit_length())  # (a power of two: a longer trial rebuilds it seldom)
    return _harmonic_tables_of_length(texture, dx_m, n_table)


@functools.lru_cache(maxsize=4)  # (2 tables × harmonics × 16384 positions: the library's most, 10 harmonics, 2.6 MB
# at default, 10.5 MB at reference)
def _harmonic_tables_of_length(texture: Texture, dx_m: float, n_table: int) -> tuple:
    k, amp = (np.array(v) for v in _harmonics(texture))
    arg = k[:, None] * (np.arange(n_table) * dx_m)[None, :]
    tables = (k, amp, np.cos(arg), np.sin(arg))
    for a in tables:
        a.setflags(write=False)
    return tables


def surface_track(texture: Texture, dx_m: float, start_m: float = 0.0, length_m: float = SURFACE_LENGTH_M) -> SurfaceTrack:
    """The texture along a straight track starting at ``start_m`` (m) on its surface, sampled every ``dx_m``."""
    if not (dx_m > 0 and math.isfinite(dx_m)):
        raise ValueError(f"dx_m = {dx_m!r}: must be a positive length in m")
    rough = random_profile(texture, dx_m, length_m)
    x = np.arange(rough.size) * dx_m
    heights = rough + periodic_profile(texture, x)
    return SurfaceTrack(np.roll(heights, -int(round(start_m / dx_m)) % heights.size), dx_m, start_m=0.0)

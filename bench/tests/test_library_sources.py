"""The texture library against its own sources and against D's rig (docs/experiment/library_checks.md).

* consistency: every texture's friction follows the class rule the library's header states and cites, so no
  single texture's µ can drift from its class without a sourced override (named in its ``source``);
* consistency with D: the rig's stroke and the skin's contact patch fit on D's 75 mm texture squares;
* derived: the roughness of a trial scatters like the sampling variance of a stationary vibration, so its σ over
  trials falls about as 1/√T with the measurement window T (the size of the window lever).
"""

import dataclasses
import math
import re

import numpy as np
import pytest

from bench.rigs.texture_rig import Movement, RigSettings, TextureRig, movement_grid
from bench.textures.library import load_library, texture
from bench.textures.properties import roughness
from emulator.params import SensorParams
from emulator.skin import Skin, contact_patch_radius_m

pytestmark = pytest.mark.unit

#: The header of fixtures/textures/library.toml ("friction"): solids (µ_smooth, µ_rough) — µs = µ_rough +
#: (µ_smooth − µ_rough)·exp(−Rq_micro / 1 µm), µk = 0.8 µs, mu_per_velocity = 2 s/m × (µs − µ_rough).
SOLID_CLASSES = {"hard": (1.2, 0.7), "polymer": (1.0, 0.65), "soft polymer": (1.1, 0.75), "elastomer": (1.3, 0.9),
                 "polyolefin": (0.65, 0.55), "PTFE": (0.35, 0.30), "graphite": (0.30, 0.25),
                 "cellulose": (0.9, 0.6)}
#: Fibre classes: µs, µk = 0.85 µs, no speed term (skin on fabrics 0.3–0.6; Derler & Gerhardt 2012).
FIBRE_CLASSES = {"cellulose fibre": 0.55, "microfibre": 0.55, "wool": 0.5, "leather nap": 0.5, "silk": 0.45,
                 "synthetic filament": 0.45, "acrylic fibre": 0.45, "hair": 0.4}
_CLASS = re.compile(r"μ: ([A-Za-z ]+?) class(?:, micro-Rq ([0-9.]+) µm)?")
#: A texture may leave its class only with a measurement named in its source (e.g. "μ measured: Author year").
_MEASURED = "μ measured:"
#: D ch. 6: "These textures were cut into 75mm x 75mm squares".
D_TEXTURE_SQUARE_M = 0.075


def _class_friction(source: str) -> tuple[float, float, float] | None:
    """(µs, µk, mu_per_velocity s/m) the class named in ``source`` gives, or None when it names none."""
    m = _CLASS.search(source)
    if m is None:
        return None
    name, rq_um = m.group(1), m.group(2)
    if name in FIBRE_CLASSES:
        mu = FIBRE_CLASSES[name]
        return mu, 0.85 * mu, 0.0
    smooth, rough = SOLID_CLASSES[name]
    mu = rough + (smooth - rough) * math.exp(-float(rq_um))
    return mu, 0.8 * mu, 2.0 * (mu - rough)


def _off_class(lib: dict) -> list[str]:
    """The textures whose friction is not their cited class's rule (and whose source names no measurement)."""
    off = []
    for n, t in lib.items():
        if _MEASURED in t.source:
            continue
        expected = _class_friction(t.source)
        if expected is None:
            off.append(f"T{n} {t.name}: its source names no friction class and no measurement")
            continue
        mus, muk, per_v = expected
        got = (t.mu_static, t.mu_kinetic, t.mu_per_velocity_s_per_m)
        if abs(got[0] - mus) > 2e-3 or abs(got[1] - muk) > 2e-3 or abs(got[2] - per_v) > 0.011:
            off.append(f"T{n} {t.name}: (µs, µk, dµ/dv) = {got}, class rule {tuple(round(x, 3) for x in expected)}")
    return off


def test_every_texture_friction_follows_its_cited_class():
    """Consistency: all 119 textures' µs, µk and speed term are their class's rule to the library's 3 decimals
    (± 0.002; the speed term ± 0.011, written to 2 decimals), unless the source names a measurement."""
    off = _off_class(load_library())
    assert not off, "textures off their friction class:\n" + "\n".join(off)


def test_the_class_rule_catches_a_texture_moved_off_its_class():
    """The check is not vacuous: ripstop (T86) given µs 0.50 with no measurement in its source is reported;
    the same value with "μ measured:" in its source is accepted."""
    lib = load_library()
    moved = dict(lib)
    moved[86] = dataclasses.replace(lib[86], mu_static=0.50)
    assert [line.split(":")[0] for line in _off_class(moved)] == ["T86 nylon ripstop"]
    moved[86] = dataclasses.replace(moved[86], source=moved[86].source + "; μ measured: (a named source)")
    assert _off_class(moved) == []


def test_stroke_and_contact_patch_fit_on_ds_texture_squares():
    """Consistency with D: the rig's square is D's 75 mm; the 5 cm stroke plus the contact patch's diameter at the
    grid's largest force (2 N) fits on it, leaving ≥ 15 mm for the random start (here 18.7 mm)."""
    settings = RigSettings()
    assert settings.texture_side_m == D_TEXTURE_SQUARE_M
    force = max(m.force_N for m in movement_grid())
    patch = 2 * contact_patch_radius_m(force, SensorParams().contact_radius_at_1N_m)
    assert D_TEXTURE_SQUARE_M - settings.distance_m - patch >= 0.015, (settings.distance_m, patch)


def test_roughness_sigma_falls_about_as_one_over_root_window():
    """Derived: 128 trials × 2 textures (T85 taffeta, T1 copy paper) slid 6.5 cm at 0.2 N, 6.31 cm/s; roughness
    over nested windows of 0.1 / 0.4 s and 0.2 / 0.8 s from 0.15 s after the slide starts. Sampling variance of
    a stationary vibration over independent stretches (starts anywhere on a 1 m texture: on D's 75 mm square the
    strokes overlap and share their windows' track): σ ratio 2 for 4× the window. Accepted 1.4–2.8 (geometric mean
    of the four ratios; measured 2.02, per texture and pair 1.75, 2.12, 1.98, 2.24). The statistic is a ratio of
    standard deviations of a heavy-tailed property, so it needs many trials: over 512 trials (seeds 40 000–40 511)
    it is 2.05, and disjoint blocks of 16 trials a texture scatter with SD 0.33 (1.51–2.86: the 16 trials this test
    used until 2026-11-24 gave 1.53, near the band's edge, and 1 block in 32 fell outside it), of 64 with SD 0.22
    (1.78–2.30), of 128 with SD 0.10 (1.92–2.16)."""
    rig = TextureRig(settings=RigSettings(distance_m=0.065, texture_side_m=1.0), skin=Skin(), wear=False)
    windows = (0.1, 0.4, 0.2, 0.8)
    ratios = []
    for number in (85, 1):
        rows = []
        for k in range(128):
            rec = rig.run_trial(texture(number), Movement(0.2, 0.0631), seed=40_000 + k).recording
            d = rec.slide_end_s - rec.slide_start_s
            rows.append([roughness(rec, 0.15 / d, 1.0 - (0.15 + w) / d) for w in windows])
        s = np.std(np.array(rows), axis=0, ddof=1)
        ratios += [s[0] / s[1], s[2] / s[3]]
    mean_ratio = float(np.exp(np.mean(np.log(ratios))))
    assert 1.4 <= mean_ratio <= 2.8, f"σ ratio for 4× the window: {mean_ratio:.2f} (per pair {np.round(ratios, 2)})"

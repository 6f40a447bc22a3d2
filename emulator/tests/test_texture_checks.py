"""A texture made in Python is checked as the friction model needs it (the library checks its own, narrower ranges)."""

import dataclasses

import pytest

from emulator.texture import Texture

GOOD = Texture(907, "good", "test", rms_height_m=1e-6, correlation_length_m=50e-6, hurst=0.8, mu_static=0.9,
               mu_kinetic=0.6, seed=1)


@pytest.mark.parametrize("field, value", [("mu_kinetic", 0.0), ("mu_static", -0.1), ("mu_kinetic", float("nan")),
                                          ("stribeck_velocity_m_per_s", 0.0), ("mu_static", float("inf"))])
def test_a_friction_the_model_cannot_take_is_refused_by_name(field, value):
    with pytest.raises(ValueError, match=f"texture 907 \\(good\\): {field} = "):
        dataclasses.replace(GOOD, **{field: value})


def test_kinetic_friction_above_static_is_refused():
    with pytest.raises(ValueError, match="mu_kinetic = 1.0 must not exceed mu_static = 0.9"):
        dataclasses.replace(GOOD, mu_kinetic=1.0)


def test_a_nearly_frictionless_texture_is_still_allowed():
    assert dataclasses.replace(GOOD, mu_static=1e-6, mu_kinetic=1e-6).mu_kinetic == 1e-6

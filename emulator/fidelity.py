"""Fidelity profiles: what accuracy costs in time.

A profile sets the simulation grid (the 4.4 kHz slot rate times an oversampling factor), how
each analog stage is discretized, and which second-order effects run (the reference profile also resolves each
fingerprint ridge's catch and release).  ``scripts/benchmark``
measures every profile's error against ``reference`` and its cost per simulated second.
"""

from __future__ import annotations

from dataclasses import dataclass

from emulator.channels import DEFAULT_SLOT_RATE_HZ

#: the fingerprint ridge models a profile may choose (see :class:`Fidelity`)
RIDGE_MODELS = ("effective", "resolved")


@dataclass(frozen=True)
class Fidelity:
    name: str
    oversampling: int  # grid rate = 4.4 kHz x oversampling
    discretization: str  # see emulator.filters.DISCRETIZATIONS
    duct_resonance: bool  # 18.7 kHz closed-tube resonance of the fluid duct
    stage2_noise: bool  # second-stage amplifier noise
    electrode_rate_Hz: float  # rate of the electrode geometry model (the channels' bandwidth is 100 Hz)
    sliding_dx_m: float  # spatial resolution of texture tracks (features finer than 2·dx are absent)
    friction_substeps: int  # friction integrated at the grid rate × substeps
    patch_radii: int  # patch radii tabulated for the contact patch (interpolated between)
    description: str
    #: fingerprint ridges: "effective" (a rigid comb, the slope table) or "resolved" (each ridge under the patch a
    #: compliant element that catches and releases; :mod:`emulator.friction`)
    ridges: str = "effective"

    def __post_init__(self):
        if self.ridges not in RIDGE_MODELS:
            raise ValueError(f"fidelity {self.name!r}: ridges = {self.ridges!r}; choose one of: {', '.join(RIDGE_MODELS)}")

    @property
    def grid_Hz(self) -> float:
        return DEFAULT_SLOT_RATE_HZ * self.oversampling


PROFILES: dict[str, Fidelity] = {
    p.name: p
    for p in (
        Fidelity("fast", 1, "bilinear", False, False, 250.0, 20e-6, 1, 4,
                 "4.4 kHz grid, plain bilinear (the 1040 Hz corner is warped), electrodes at 250 Hz, "
                 "textures at 20 µm, friction on the grid, 4 patch radii, first-order effects only"),
        Fidelity("default", 2, "prewarped", False, False, 500.0, 10e-6, 1, 8,
                 "8.8 kHz grid, every corner prewarped, electrodes at 500 Hz, textures at 10 µm, friction on the "
                 "grid, 8 patch radii, first-order effects only"),
        Fidelity("reference", 16, "prewarped", True, True, 2000.0, 2.5e-6, 4, 16,
                 "70.4 kHz grid, prewarped, electrodes at 2 kHz, textures at 2.5 µm, friction oversampled ×4, "
                 "16 patch radii, ridge-resolved fingerprints, plus duct resonance and second-stage noise",
                 ridges="resolved"),
    )
}


def profile(name: str) -> Fidelity:
    try:
        return PROFILES[name]
    except KeyError:
        raise ValueError(f"unknown fidelity profile {name!r}; choose one of: {', '.join(PROFILES)}") from None

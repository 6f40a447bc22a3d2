"""The linear stage's motor: how a rig measures traction (D ch. 6: the motor current rises linearly with the
tangential load while the stage drags the texture under the finger)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class StageMotor:
    """Current (A) = idle + slope × |the stage's load| + current-sense noise, the load being the tangential force
    through the stage's mechanics (``stage_force_N``, low-passed at 20 Hz); all are model choices (D: "linear")."""

    idle_A: float = 0.15
    A_per_N: float = 0.4
    noise_A: float = 0.004  # RMS per reading

    def current_A(self, tangential_N, rng: np.random.Generator) -> np.ndarray:
        """Motor current (A) for tangential loads (N), one noisy reading each."""
        ft = np.asarray(tangential_N, float)
        return self.idle_A + self.A_per_N * np.abs(ft) + self.noise_A * rng.standard_normal(ft.size)

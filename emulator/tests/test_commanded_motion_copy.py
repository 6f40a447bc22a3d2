"""A sensor driven by a commanded motion, copied together with its motion (as the texture rig snapshots its run and
goes back to the copy): every part of the copy follows the copied motion's later commands, none the original's."""

import copy

import numpy as np
import pytest

from emulator.channels import ELECTRODE_FIRST
from emulator.electrodes import electrode_positions_mm, surface_point_mm
from emulator.sensor import NoiseSources, Sensor
from emulator.sliding import CommandedMotion
from emulator.texture import Texture

SAND = Texture(901, "sand", "test", rms_height_m=60e-6, correlation_length_m=270e-6, hurst=0.8, mu_static=0.9,
               mu_kinetic=0.6, modulus_Pa=5e9, seed=7)


@pytest.mark.unit
def test_a_copied_sensors_electrodes_follow_the_copied_motion():
    """The copy stops its finger; the original keeps lowering.  The copy's electrode under the pad holds near the
    stopped finger's reading, far from the original's deeper press (before the fix the copy's electrodes read the
    original motion through a closure and followed the finger that kept lowering)."""
    nearest = int(np.argmin(np.linalg.norm(electrode_positions_mm() - surface_point_mm(-5.0, 0.0), axis=1))) + 1
    index = ELECTRODE_FIRST + nearest - 1
    motion = CommandedMotion(SAND, latency_s=0.02, start_s=0.0, depth_m=-2e-4)
    sensor = Sensor(stimuli=[motion], channels_read=[f"E{nearest}"], noise=NoiseSources.none())
    motion.move_finger(0.0, 1e-3)  # lower at 1 mm/s from 20 ms
    sensor.sample([index], [0.5])
    sensor_copy, motion_copy = copy.deepcopy((sensor, motion))
    motion_copy.move_finger(0.5, 0.0)  # the copy's finger stops at 0.52 s, ~0.3 mm into the skin
    stopped_early = float(sensor_copy.sample([index], [0.6])[0])
    stopped_late = float(sensor_copy.sample([index], [1.5])[0])
    deeper = float(sensor.sample([index], [1.5])[0])  # the original: ~1.3 mm into the skin by 1.5 s
    assert abs(stopped_late - stopped_early) < abs(deeper - stopped_early) / 4
    assert stopped_late - deeper > 20

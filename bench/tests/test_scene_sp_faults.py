"""A scene's sensor faults number electrodes as its sensors do: a scene of BioTac SPs can fault E20..E24 (the SP's
24 electrodes), a 19-electrode scene cannot, and a scene mixing the two cannot either in its [faults] (every sensor
has them; an SP's own [sensor.faults] can: bench/tests/test_scene_sensor_faults.py) — each refusal names the field,
the value and the allowed range.  (The scene format allowed 1..19 only, whatever the variant, though the emulator's
sensors accept 1..24 on an SP.)"""

import numpy as np
import pytest

from bench.errors import SceneError
from bench.scenes.scene import parse_scene_text
from emulator.channels import channel_index
from emulator.sensor import NoiseSources, Sensor

SCENE = """
[scene]
name = "sp-faults"
duration_s = 1.0
{sensor}
[faults]
{faults}
"""
SP = '[sensor]\nvariant = "biotac-sp"'


@pytest.mark.unit
def test_a_biotac_sp_scene_faults_its_extra_electrodes():
    scene = parse_scene_text(SCENE.format(sensor=SP, faults="electrode_open = [22]\nmux_stuck = 24"), "sp.toml")
    assert scene.faults == {"electrode_open": [22], "mux_stuck": 24}
    sensor = Sensor(channels_read=["E22", "E1"], variant="biotac-sp", faults={"electrode_open": [22]},
                    noise=NoiseSources.none())
    codes = sensor.sample(np.array([channel_index("E22")] * 3), np.array([0.1, 0.1002, 0.1004]))
    assert codes[-1] < 100  # an open electrode reads near the bottom rail


@pytest.mark.unit
@pytest.mark.parametrize("sensor, faults, words", [
    ("", "electrode_open = [22]", "faults.electrode_open = [22]: a list of electrode numbers 1..19 (every sensor"),
    ("", "mux_stuck = 20", "faults.mux_stuck = 20: allowed range is 1 to 19"),
    (SP, "electrode_short = [25]", "faults.electrode_short = [25]: a list of electrode numbers 1..24"),
    (SP + '\n[[sensors]]\nindex = 2\nvariant = "biotac"', "electrode_open = [21]",
     "a list of electrode numbers 1..19 (every sensor of the scene has the [faults]; a \"biotac-sp\"'s E20..E24 go "
     "in its own [sensor.faults] or [sensors.faults])"),
])
def test_electrode_faults_beyond_a_sensors_electrodes_are_refused_by_name(sensor, faults, words):
    with pytest.raises(SceneError) as e:
        parse_scene_text(SCENE.format(sensor=sensor, faults=faults), "f.toml")
    assert words in str(e.value)

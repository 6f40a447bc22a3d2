"""Values each within its range that no sensor or stimulus can have together (from a hostile pass): refused when the
scene is read — by `validate` as by `run` — with the field and value named, before `run --force` removes anything;
never a run that fails at 0 s, a stimulus that silently does nothing or electrodes that respond backwards."""

import dataclasses

import pytest

from bench.cli import main as cli
from bench.errors import SceneError
from bench.paths import SCENES_DIR
from bench.running.runner import check_buildable
from bench.scenes.scene import load_scene
from emulator.params import SensorParams
from emulator.stimuli import PressureCalibrator

pytestmark = pytest.mark.unit

IMPOSSIBLE = """
[scene]
name = "impossible"
duration_s = 1.0
[sensor]
resting_gap_mm = 0.2
minimum_gap_mm = 1.0
"""


def test_run_force_with_an_impossible_sensor_keeps_the_earlier_run(tmp_path, capsys):
    """The earlier run's files are all still there and unchanged; exit 2 with the scene's file and field named."""
    out = tmp_path / "o"
    assert cli.main(["run", str(SCENES_DIR / "rest.toml"), "--out", str(out), "--quiet", "--no-plots"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    scene = tmp_path / "impossible.toml"
    scene.write_text(IMPOSSIBLE)
    capsys.readouterr()
    assert cli.main(["run", str(scene), "--out", str(out), "--force", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(scene) in err and "minimum_gap_mm = 1 mm must be below" in err and "Traceback" not in err, err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_a_sensor_that_cannot_be_built_is_a_scene_error_before_anything_runs(tmp_path):
    """check_buildable builds each sensor as the run would first: a scene changed in Python after it was read (the
    reading would refuse it) whose second sensor is given a 3 kHz tone the fast profile's 4.4 kHz grid cannot hold
    is refused, naming the sensor; the shipped scenes all build."""
    from emulator.stimuli import Vibration

    scene = load_scene(SCENES_DIR / "grasp_three_fingers.toml")
    for k in (2, 3):  # a middle finger and the last
        spec = scene.sensor_spec(k)
        too_high = dataclasses.replace(spec, stimuli=[*spec.stimuli, Vibration(0.1, 0.2, 1e-6, 3000.0)])
        broken = dataclasses.replace(scene, fidelity="fast", sensors={**scene.sensors, k: too_high})
        with pytest.raises(SceneError, match=rf"sensor {k}: vibration at 3000 Hz needs a finer grid than 4400 Hz"):
            check_buildable(broken)
    for path in sorted(SCENES_DIR.glob("*.toml")):
        check_buildable(load_scene(path))


def test_the_python_api_refuses_the_same_combinations():
    with pytest.raises(ValueError, match="amplitude_Pa = 1000.0 needs frequency_Hz > 0"):
        PressureCalibrator(0.1, 0.8, amplitude_Pa=1000.0)
    assert PressureCalibrator(0.1, 0.8, offset_Pa=500.0).value([0.5])[0] == pytest.approx(500.0)  # steady: no wave
    with pytest.raises(ValueError, match="minimum_gap_mm = 0.9 mm must be below sensor.resting_gap_mm = 0.5 mm"):
        SensorParams().replace(minimum_gap_mm=0.9, resting_gap_mm=0.5)
    with pytest.raises(ValueError, match="electrode_gap_seed = 2.5: must be a whole number"):
        SensorParams().replace(electrode_gap_seed=2.5)
    assert SensorParams().replace(electrode_gap_seed=7.0).electrode_gap_seed == 7.0  # a whole float is a whole number

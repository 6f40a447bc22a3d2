"""record.json carries the whole scene as run (README, Outputs): the noise switches and every sensor parameter,
with the scene's own overrides; checked on a short run built from a scene that changes both."""

import dataclasses

import pytest

from bench.reporting.report import build_record
from bench.running.runner import run_scene
from bench.scenes.scene import parse_scene
from emulator.params import SensorParams

pytestmark = pytest.mark.unit


def test_the_record_holds_the_noise_switches_and_every_sensor_parameter_as_run():
    scene = parse_scene({"scene": {"name": "fields", "duration_s": 0.3, "seed": 5},
                         "sensor": {"resonance_Hz": 300.0}, "noise": {"adc": False, "mains_hum": False},
                         "host": {"sequence": ["PAC", "PDC"]}})
    record = build_record(run_scene(scene, progress=False), [])
    assert record["noise"]["adc"] is False and record["noise"]["mains_hum"] is False
    assert record["noise"]["johnson"] is True  # the switches not named keep their defaults
    nominal = dataclasses.asdict(SensorParams())
    assert set(record["sensor_parameters"]) == set(nominal)
    assert record["sensor_parameters"]["resonance_Hz"] == 300.0
    assert all(record["sensor_parameters"][k] == v for k, v in nominal.items() if k != "resonance_Hz")
    assert record["host"]["spi"] == "software" and record["scene"]["seed"] == 5

"""Bad values given to the pytest plugin's factories (and to the sensors and benches behind them) are refused
with one message naming the keyword and the value: a fault value that would be silently misread (a thermistor
fault "melted" left the thermistor healthy, ``heater_failed="no"`` killed the heater), a flag given as a word
("no" is truthy, or a traceback from inside a HAL call), a seed that is not a number, a sensor that is not a
Sensor."""

from __future__ import annotations

import pytest

from bench.scenes.limits import SEED_SAID
from emulator.sensor import Sensor

pytestmark = pytest.mark.firmware
pytest_plugins = ["pytester"]


@pytest.mark.parametrize("faults, message", [
    ({"thermistor": "melted"}, "faults.thermistor = 'melted': must be \"open\" or \"short\""),
    ({"thermistor": True}, "faults.thermistor = True"),
    ({"heater_failed": "no"}, "faults.heater_failed = 'no': must be True or False"),
    ({"heater_failed": 1}, "faults.heater_failed = 1"),
    ({"electrode_open": 3}, "faults.electrode_open = 3: must be a list of electrode numbers"),
    ({"electrode_short": "5"}, "faults.electrode_short = '5'"),
])
def test_a_sensor_refuses_fault_values_it_would_misread(faults, message):
    with pytest.raises(ValueError) as e:
        Sensor(faults=faults, channels_read=["PDC", "TDC", "E1"])
    assert message in str(e.value)


def test_the_sensor_faults_a_scene_can_give_are_still_taken():
    for faults in ({"thermistor": "open"}, {"thermistor": "short"}, {"heater_failed": True},
                   {"heater_failed": False}, {"electrode_open": [3], "electrode_short": (5,)}):
        Sensor(faults=faults, channels_read=["PDC", "TDC", "E1"])


def test_a_set_of_electrode_numbers_opens_the_same_electrodes_as_a_list():
    """A Python caller may give the open or shorted electrodes as a set ({7, 3}): the sensor reads exactly as with
    the list [3, 7] (E3 and E7 near 0, E1 untouched), and keeps them as that list (what records and scenes hold)."""
    import numpy as np

    from emulator import channels as ch

    t = np.arange(1, 40) * 1e-3
    read = []
    for opened in ({7, 3}, [3, 7]):
        s = Sensor(faults={"electrode_open": opened}, channels_read=["E1", "E3", "E7"], seed=4)
        read.append(s.sample([ch.channel_index(e) for e in ("E1", "E3", "E7")] * 13, t))
        assert s.faults["electrode_open"] == [3, 7]
    assert np.array_equal(read[0], read[1])
    e1, e3, e7 = read[0][0::3], read[0][1::3], read[0][2::3]
    assert e3.max() < 40 and e7.max() < 40 and e1.min() > 1000


MISUSE = '''
def test_thermistor(biotac_sensor):
    biotac_sensor(faults={"thermistor": "melted"})

def test_pull_up_word(biotac_bridge):
    biotac_bridge(pull_up="no")

def test_realtime_word(biotac_bridge):
    biotac_bridge(realtime="yes")

def test_keep_arrivals_number(biotac_bridge):
    biotac_bridge(keep_arrivals=3)

def test_trace_word(biotac_cheetah):
    biotac_cheetah(trace="x")

def test_bridge_seed_word(biotac_bridge):
    biotac_bridge(seed="a")

def test_scene_seed_word(biotac_sensor):
    biotac_sensor(scene="taps", seed="x")

def test_not_a_sensor(biotac_bridge):
    biotac_bridge(sensors={1: 3})
'''


def test_a_numpy_seed_is_still_a_seed(biotac_sensor, biotac_bridge):
    import numpy as np

    assert biotac_sensor(seed=np.int64(3)).sensor.seed == 3
    biotac_bridge(seed=np.int64(3))


def test_bad_values_fail_the_users_test_naming_the_keyword(pytester):
    pytester.makepyfile(test_user=MISUSE)
    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(failed=8)
    result.stdout.fnmatch_lines([
        "*biotac_sensor(): faults.thermistor = 'melted': must be \"open\" or \"short\"*",
        "*biotac_bridge(): pull_up = 'no': must be True or False*",
        "*biotac_bridge(): realtime = 'yes': must be True or False*",
        "*biotac_bridge(): keep_arrivals = 3: must be True or False*",
        "*biotac_cheetah(): trace = 'x': must be True or False*",
        f"*biotac_bridge(): seed = 'a': {SEED_SAID}*",
        f"*biotac_sensor(): seed = 'x': {SEED_SAID}*",
        "*biotac_bridge(): sensors = {1: 3}: each must be an emulator.sensor.Sensor*",
    ])
    out = result.stdout.str()
    assert "Traceback" not in out and "FirmwareError" not in out and "AttributeError" not in out, out


def test_numpy_bools_are_still_flags(biotac_bridge, biotac_cheetah):
    """A flag from numpy (a parametrized array's element, a comparison's result) is True or False: the flag checks
    took only Python's bool and refused np.True_ and np.False_, which had worked."""
    import numpy as np

    bench = biotac_bridge(pull_up=np.False_, realtime=np.False_, keep_arrivals=np.True_)
    assert bench.realtime is False
    assert biotac_cheetah(trace=np.True_).trace is not None

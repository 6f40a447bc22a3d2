"""The pytest plugin's session-wide conventions: one seed convention for every factory and route (sensor k of a
call or session with seed S draws seed ``S + k - 1``), the session's ``--biotac-fidelity``/``--biotac-seed`` (and
their ini values ``biotac_fidelity``/``biotac_seed``) under a test's ``biotac`` marker and its calls' keywords.
The users' sessions run in subprocesses (numpy and numba refuse to be loaded a second time in one process)."""

from __future__ import annotations

import numpy as np
import pytest

from bench.scenes.limits import MAX_SEED, SEED_SAID

pytestmark = pytest.mark.firmware
pytest_plugins = ["pytester"]

#: When the noise of each route's sensors is compared (s): long after any start-up traffic, 300 PAC samples.
NOISE_TIMES_S = 2.0 + np.arange(300) / 4400.0


def pac_noise(sensor) -> np.ndarray:
    """``sensor``'s PAC codes at :data:`NOISE_TIMES_S` (at rest: its noise around the rest level)."""
    from emulator.channels import PAC

    return sensor.sample(np.full(NOISE_TIMES_S.size, PAC), NOISE_TIMES_S)


def test_sensor_k_draws_the_same_noise_whichever_factory_or_route_makes_it(biotac_sensor, biotac_bridge,
                                                                            biotac_cheetah):
    """Sensor k of seed S, at rest, gives the same PAC codes from biotac_sensor (sensor 1), the bridge and the
    Cheetah adapter, each with and without a scene (the shipped "rest": a nominal sensor, every noise source on):
    one convention, ``S + k - 1``, everywhere; and sensors 1..3 differ from one another."""
    seed, n = 11, 3
    bridges = [biotac_bridge(n_sensors=n, seed=seed), biotac_bridge(scene="rest", n_sensors=n, seed=seed)]
    for bridge in bridges:  # its firmware no longer samples the sensors (compared from this thread)
        bridge.stop()
    routes = {"bridge": bridges[0].board.sensors, "bridge, scene": bridges[1].board.sensors}
    for name, kw in (("cheetah", {}), ("cheetah, scene", {"scene": "rest"})):
        routes[name] = {k: p.sensor for k, p in biotac_cheetah(n_sensors=n, seed=seed, **kw).bus.ports.items()}
    routes["sensor"] = {1: biotac_sensor(seed=seed).sensor}
    routes["sensor, scene"] = {1: biotac_sensor(scene="rest", seed=seed).sensor}
    noise = {name: {k: pac_noise(s) for k, s in sensors.items()} for name, sensors in routes.items()}
    for k in range(1, n + 1):
        reference = noise["bridge"][k]
        assert np.ptp(reference) > 0, f"sensor {k}: no noise to compare"
        for name, by_sensor in noise.items():
            if k in by_sensor:
                assert np.array_equal(by_sensor[k], reference), f"sensor {k}: {name} draws other noise than the bridge"
                assert routes[name][k].seed == seed + k - 1, (name, k, routes[name][k].seed)
    assert not np.array_equal(noise["bridge"][1], noise["bridge"][2])
    assert not np.array_equal(noise["bridge"][2], noise["bridge"][3])



def test_the_benches_and_default_sensors_number_sensors_as_every_route_does(biotac_sensor):
    """Outside the plugin too — ``FirmwareBench``, ``CheetahBench`` (and so ``biotac-bench bridge`` / ``cheetah
    serve`` without a scene) and ``default_sensors`` — sensor k of seed S draws ``S + k - 1``, from a default seed
    of 0: a bench's sensor 1 without a seed gives biotac_sensor()'s codes (they drew seed + k from 1 before)."""
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.cheetah_server import CheetahBench
    from bench.hosts.cosim import default_sensors

    firmware = FirmwareBench(n_sensors=3, seed=11)
    firmware.stop()
    cheetah = CheetahBench(n_sensors=3, seed=11)
    for name, sensors in (("FirmwareBench", firmware.board.sensors), ("default_sensors", default_sensors(3, seed=11)),
                          ("CheetahBench", {k: p.sensor for k, p in cheetah.bus.ports.items()})):
        assert [sensors[k].seed for k in (1, 2, 3)] == [11, 12, 13], name
    unseeded = FirmwareBench(n_sensors=2)
    unseeded.stop()
    assert [unseeded.board.sensors[k].seed for k in (1, 2)] == [0, 1]
    assert [p.sensor.seed for p in CheetahBench(n_sensors=2).bus.ports.values()] == [0, 1]
    assert np.array_equal(pac_noise(unseeded.board.sensors[1]), pac_noise(biotac_sensor().sensor))

SETTINGS_SEEN = '''
import pytest

def seen(sensors):
    return [(s.fidelity.name, s.seed) for s in sensors]

def test_session(biotac_sensor, biotac_bridge, biotac_cheetah):
    assert seen([biotac_sensor().sensor]) == [{session}]
    assert seen(biotac_bridge(n_sensors=2).board.sensors.values()) == {session_two}
    assert seen(p.sensor for p in biotac_cheetah(n_sensors=2).bus.ports.values()) == {session_two}
    assert seen([biotac_sensor(scene="rest").sensor]) == [{scene}]

@pytest.mark.biotac(fidelity="reference", seed=40)
def test_marker(biotac_sensor, biotac_bridge):
    assert seen([biotac_sensor().sensor]) == [("reference", 40)]
    assert seen(biotac_bridge(n_sensors=2).board.sensors.values()) == [("reference", 40), ("reference", 41)]
    assert seen([biotac_sensor(fidelity="fast", seed=3).sensor]) == [("fast", 3)]  # the call wins

def test_the_call_decides(biotac_cheetah):
    assert seen(p.sensor for p in biotac_cheetah(seed=5, fidelity="default").bus.ports.values()) == [("default", 5)]

@pytest.mark.biotac(fidelity="reference")
def test_the_call_decides_beside_a_scene(biotac_sensor, biotac_bridge, biotac_cheetah):
    def profiles(sensors):
        return [name for name, _ in seen(sensors)]

    assert profiles([biotac_sensor(scene="rest", fidelity="fast").sensor]) == ["fast"]
    assert profiles(biotac_bridge(scene="rest", fidelity="fast").board.sensors.values())[0] == "fast"
    assert profiles(p.sensor for p in biotac_cheetah(scene="rest", fidelity="fast").bus.ports.values())[0] == "fast"
    assert profiles([biotac_sensor(scene="rest").sensor]) == ["reference"]  # the marker's, without the call's
'''


@pytest.mark.parametrize("options, ini, session, scene", [
    ([], "", ("default", 0), ("default", 7)),  # "rest" says seed 7, fidelity default
    (["--biotac-fidelity", "fast", "--biotac-seed", "21"], "", ("fast", 21), ("fast", 21)),
    ([], "biotac_fidelity = fast\nbiotac_seed = 30\n", ("fast", 30), ("fast", 30)),
    (["--biotac-seed=9"], "biotac_fidelity = reference\nbiotac_seed = 30\n", ("reference", 9), ("reference", 9)),
])
def test_the_sessions_fidelity_and_seed_reach_every_factory_under_the_tests_marker_and_call(pytester, options, ini,
                                                                                            session, scene):
    """Without settings every factory's sensor 1 draws seed 0 at the default profile (a scene's sensors its own);
    ``--biotac-fidelity``/``--biotac-seed``, or the ini values, set every factory's sensors (a scene's too), the
    command line over the ini; a test's ``biotac`` marker over the session, a call's keywords over both."""
    fidelity, seed = session
    pytester.makepyfile(test_user=SETTINGS_SEEN.format(session=session, scene=scene,
                                                       session_two=[(fidelity, seed), (fidelity, seed + 1)]))
    if ini:
        pytester.makeini("[pytest]\n" + ini)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", *options)
    result.assert_outcomes(passed=4)
    assert "warning" not in result.stdout.str().lower(), result.stdout.str()


@pytest.mark.parametrize("options, ini, line", [
    (["--biotac-fidelity=slow"], "", "ERROR: --biotac-fidelity = 'slow': a fidelity profile, one of fast, default, "
                                     "reference"),
    (["--biotac-seed", "-3"], "", f"ERROR: --biotac-seed = '-3': {SEED_SAID}"),
    ([], "biotac_seed = 1.5\n", f"ERROR: ini value biotac_seed = '1.5': {SEED_SAID}"),
    ([], "biotac_fidelity = Fast\n", "ERROR: ini value biotac_fidelity = 'Fast': a fidelity profile, one of fast, "
                                     "default, reference"),
    # past a scene's bound (2**63 - 1): refused as a scene's seed is, though no scene is given
    (["--biotac-seed", str(MAX_SEED + 1)], "", f"ERROR: --biotac-seed = '{MAX_SEED + 1}': {SEED_SAID}"),
    ([], f"biotac_seed = {MAX_SEED + 1}\n", f"ERROR: ini value biotac_seed = '{MAX_SEED + 1}': {SEED_SAID}"),
])
def test_a_sessions_setting_that_is_not_one_stops_the_session_at_its_start_in_one_line(pytester, options, ini, line):
    """A bad ``--biotac-fidelity``/``--biotac-seed`` or ini value: no test runs, exit code 4 (a usage error), and
    the one line names the option or ini value, the value and what it may be."""
    pytester.makepyfile(test_user="def test_x():\n    pass\n")
    if ini:
        pytester.makeini("[pytest]\n" + ini)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", *options)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert [x for x in result.stderr.lines if x.strip()] == [line], result.stderr.lines
    assert "passed" not in result.stdout.str()


MARKER_MISUSED = '''
import pytest

@pytest.mark.biotac(fidelity="slow")
def test_bad_fidelity(biotac_sensor):
    pass

@pytest.mark.biotac(sed=3)
def test_unknown_keyword(biotac_bridge):
    pass

@pytest.mark.biotac(seed=-1)
def test_bad_seed(biotac_cheetah):
    pass
'''


def test_a_marker_that_is_not_one_fails_its_test_in_one_line(pytester):
    pytester.makepyfile(test_user=MARKER_MISUSED)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-rE")
    result.assert_outcomes(errors=3)
    result.stdout.fnmatch_lines([
        "*ERROR at setup of test_bad_fidelity*",
        "@pytest.mark.biotac(): fidelity = 'slow': a fidelity profile, one of fast, default, reference",
        "*ERROR at setup of test_unknown_keyword*",
        "@pytest.mark.biotac(): sed = 3: not a setting (it takes fidelity, seed)",
        "*ERROR at setup of test_bad_seed*",
        f"@pytest.mark.biotac(): seed = -1: {SEED_SAID}",
    ], consecutive=True)
    assert "Traceback" not in result.stdout.str()


SEEDS_AT_THE_BOUND = f'''
import pytest

@pytest.mark.biotac(seed={MAX_SEED + 1})
def test_marker(biotac_bridge):
    pass

def test_sensor_call(biotac_sensor):
    biotac_sensor(seed={MAX_SEED + 1})

def test_bridge_call(biotac_bridge):
    biotac_bridge(seed={MAX_SEED + 1})

def test_cheetah_call(biotac_cheetah):
    biotac_cheetah(seed={MAX_SEED + 1})

def test_scene_call(biotac_sensor):
    biotac_sensor(scene="rest", seed={MAX_SEED + 1})

@pytest.mark.biotac(seed={MAX_SEED})
def test_the_bound_itself(biotac_bridge, biotac_sensor, biotac_cheetah):
    assert [s.seed for s in biotac_bridge(n_sensors=5).board.sensors.values()] == [{MAX_SEED} + k for k in range(5)]
    assert biotac_sensor().sensor.seed == biotac_sensor(scene="rest").sensor.seed == {MAX_SEED}
    assert biotac_cheetah(n_sensors=2, seed={MAX_SEED}).bus.ports[2].sensor.seed == {MAX_SEED + 1}
'''


def test_a_seed_past_a_scenes_bound_is_refused_alike_by_the_marker_and_every_call(pytester):
    """A scene's seed is at most 2**63 - 1 (MAX_SEED); the marker's and a call's seed= are bounded the same with or
    without a scene, in the same words (a seed past it had reached the sensors: a bare numpy TypeError without a
    scene, the scene's own message with one); the bound itself runs on every factory, sensor k drawing seed + k - 1."""
    pytester.makepyfile(test_user=SEEDS_AT_THE_BOUND)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider")
    result.assert_outcomes(passed=1, failed=4, errors=1)
    said = f"seed = {MAX_SEED + 1}: {SEED_SAID}"  # (the marker's error is listed first, then the failures)
    result.stdout.fnmatch_lines([f"@pytest.mark.biotac(): {said}", f"biotac_sensor(): {said}",
                                 f"biotac_bridge(): {said}", f"biotac_cheetah(): {said}", f"biotac_sensor(): {said}"])
    assert "Traceback" not in result.stdout.str()


SCENE_READ_AGAIN = '''
from bench.scenes.scene import load_scene


def test_slides(biotac_sensor, biotac_bridge):
    drawn = load_scene("{slides}", {{"scene.seed": 5}}).stimuli  # what `biotac-bench run --seed 5` slides over
    assert drawn != load_scene("{slides}").stimuli
    assert list(biotac_sensor(scene="{slides}").sensor.stimuli) == drawn
    bench = biotac_bridge(scene="{slides}")
    bench.stop()
    assert list(bench.board.sensors[1].stimuli) == drawn


def test_vibration(biotac_sensor):
    biotac_sensor(scene="vibration.toml")
'''


def test_a_sessions_seed_and_fidelity_reach_a_scene_as_runs_options_do(pytester):
    """``--biotac-seed``/``--biotac-fidelity`` replace a scene's own as ``biotac-bench run --seed/--fidelity`` do:
    the scene is read again with them — its slides placed from the session's seed (not the file's), and a stimulus
    the session's profile cannot compute (a 3 kHz vibration, valid at "default", past "fast"'s grid) fails its test
    in one line naming it, rather than running on a grid that cannot carry it."""
    from bench.paths import REPO

    slides = REPO / "fixtures" / "scenes" / "skin_wear.toml"
    text = (REPO / "fixtures" / "scenes" / "vibration_sweep.toml").read_text()
    assert "f_stop_Hz = 900.0" in text
    pytester.path.joinpath("vibration.toml").write_text(text.replace("f_stop_Hz = 900.0", "f_stop_Hz = 3000.0"))
    pytester.makepyfile(test_user=SCENE_READ_AGAIN.format(slides=slides))
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "--biotac-seed", "5", "--biotac-fidelity",
                                           "fast")
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(["biotac_sensor(): vibration.toml: 1 problem(s):",
                                 "  - the stimulus starting at 1 s: vibration at 3000 Hz needs a finer grid than "
                                 "fidelity 'fast' (4400 Hz); use \"default\" or \"reference\""], consecutive=True)
    assert "Traceback" not in result.stdout.str()

"""A fluid leak, the mechanical fault D ch. 3 names ("the DC pressure component of the signal can be used to detect
leakage and determine if the skin is in need of replacement"): the finger's inflation volume falls with time, and
with it the resting pressure (PDC), the share of a contact's load the fluid carries, and the fluid gap over every
electrode.  Each effect is what the model's own pressure–volume curve, fluid stiffness and wetted area predict; the
sensor is a healthy one's, to the bit, until the leak starts; the output does not depend on the block size; an
empty finger stays finite; bad values are refused by name."""

import dataclasses

import numpy as np
import pytest

from bench.errors import SceneError
from bench.scenes.scene import parse_scene_text
from emulator.channels import PAC, PDC, channel_index
from emulator.electrodes import electrode_volts, resting_gaps_mm
from emulator.mechanics import FluidLeak
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.stimuli import Press
from emulator.units import derived

QUIET = NoiseSources.none()
RATE = 0.1  # mL/min: 0.1 mL lost over the first minute after the leak starts at 1 s
LEAK = {"fluid_leak_mL_per_min": RATE, "fluid_leak_start_s": 1.0}
PUNCTURE = {"fluid_leak_mL_per_min": 6.0}  # the 0.5 mL finger empty after 5 s
P = SensorParams()
E1, E10 = channel_index("E1"), channel_index("E10")


def _volume(t_s: float) -> float:
    return max(P.inflation_volume_mL - RATE / 60.0 * max(t_s - 1.0, 0.0), 0.0)


def _pdc_at_rest(volume_mL: float) -> float:
    """The resting PDC code (unrounded) a finger filled with ``volume_mL`` reads (the published chain's figure; an
    empty finger as one with 1e-12 mL, whose pressure is nil to the code)."""
    return derived(dataclasses.replace(P, inflation_volume_mL=max(volume_mL, 1e-12)))["resting_PDC_code"]


@pytest.mark.unit
def test_the_resting_pdc_follows_the_pressure_volume_curve_down():
    """Derived: with the noise off, the resting PDC at 0.5, 20, 40, 61 and 90 s is the code the pressure–volume
    curve P = a·V^1.5 gives for the volume left (rounded: within 1 code), ~33 codes lower after the first 0.1 mL;
    a punctured finger's falls to the bridge's zero-pressure code once empty; a healthy sensor keeps its code."""
    t = np.array([0.5, 20.0, 40.0, 61.0, 90.0])
    leaking = Sensor(channels_read=["PDC"], faults=LEAK, noise=QUIET).sample(np.full(t.size, PDC), t).astype(int)
    healthy = Sensor(channels_read=["PDC"], noise=QUIET).sample(np.full(t.size, PDC), t).astype(int)
    expected = np.array([_pdc_at_rest(_volume(x)) for x in t])
    assert np.all(np.abs(leaking - expected) <= 1.0), (leaking, expected)
    assert np.all(healthy == healthy[0])
    assert healthy[0] - leaking[3] == pytest.approx(33, abs=1)
    empty = Sensor(channels_read=["PDC"], faults=PUNCTURE, noise=QUIET).sample(np.array([PDC]), np.array([6.0])).astype(int)
    assert empty[0] == pytest.approx(_pdc_at_rest(0.0), abs=1.0)
    assert healthy[0] - empty[0] > 100


def _press_rise(sensor, start: float) -> float:
    """PDC at the end of a 1 N press's hold (0.1 s ramp, 1 s hold), less PDC just before the press, codes."""
    t = np.array([start - 0.01, start + 1.1])
    c = sensor.sample(np.full(t.size, PDC), t).astype(float)
    return c[1] - c[0]


@pytest.mark.unit
def test_a_press_reaches_the_fluid_less_as_the_finger_empties():
    """Prediction: the fluid carries φ(V) = k_f/(k_f + k_s) of a held load and k_f ∝ dP/dV ∝ √V, so a 1 N press
    with 0.1 mL left (a 1 mL/min leak, 24 s in) moves PDC by φ(V)/φ(V₀) ≈ 0.83 of what it moves on a healthy
    finger, less the resting pressure the leak takes meanwhile (P(V) over the press's 1.11 s): within 1.5 codes
    (rounding twice); ~73 codes against ~88.  Once a punctured finger is empty a press moves PDC by at most 1 code."""
    start, leak = 23.9, {"fluid_leak_mL_per_min": 1.0, "fluid_leak_start_s": 1.0}
    press = [Press(start, 1.0, 0.1, 1.0)]
    healthy = _press_rise(Sensor(stimuli=press, channels_read=["PDC"], noise=QUIET), start)
    leaking = _press_rise(Sensor(stimuli=press, channels_read=["PDC"], faults=leak, noise=QUIET), start)
    fluid = FluidLeak(1.0, 1.0)
    t0, t1 = start - 0.01, start + 1.1
    gain = fluid.force_gain(P, t1)
    assert 0.8 < gain < 0.86
    rest_drop = (P.resting_pressure_at(fluid.volume_mL(0.5, t0)) - P.resting_pressure_at(fluid.volume_mL(0.5, t1))) \
        / derived(P)["PDC_Pa_per_bit"]
    assert healthy > 80
    assert leaking == pytest.approx(gain * healthy - rest_drop, abs=1.5)
    emptied = Sensor(stimuli=[Press(6.0, 1.0, 0.1, 1.0)], channels_read=["PDC"], faults=PUNCTURE, noise=QUIET)
    assert abs(_press_rise(emptied, 6.0)) <= 1


@pytest.mark.unit
def test_the_electrodes_read_gaps_thinned_with_the_fluid_lost():
    """Derived: each resting gap thins with the share of the fluid lost (the layer in proportion to the volume: a
    fifth thinner after 0.1 mL of 0.5 mL), so each electrode reads its thinner gap's voltage (within 1 code); the
    codes fall (a thinner sheet of fluid, a higher impedance); an empty finger's skin rests on the core (g_min)."""
    # each electrode read twice in a row: the multiplexer keeps 0.67 % of the conversion before, its own then
    t = np.array([0.5, 0.5002, 0.5004, 0.5006, 61.0, 61.0002, 61.0004, 61.0006])
    codes = Sensor(channels_read=["E1", "E10"], faults=LEAK, noise=QUIET).sample(
        np.array([E1, E1, E10, E10] * 2), t).astype(int)
    gaps = resting_gaps_mm(P, 19)
    lost = 1.0 - _volume(61.0) / P.inflation_volume_mL
    assert lost == pytest.approx(0.2, rel=1e-9)
    for k, electrode in ((5, 0), (7, 9)):
        volts = electrode_volts(P, (gaps * (1.0 - lost))[None, :])[0, electrode]
        assert codes[k] == pytest.approx(volts / 3.3 * 4096, abs=1.0)
        assert codes[k] < codes[k - 4] - 50
    empty = Sensor(channels_read=["E1"], faults=PUNCTURE, noise=QUIET).sample(np.array([E1] * 3),
                                                                             np.array([6.0, 6.0002, 6.0004]))
    floor = electrode_volts(P, np.full((1, 19), P.minimum_gap_mm))[0, 0]
    assert empty[-1] == pytest.approx(floor / 3.3 * 4096, abs=1.0)


@pytest.mark.unit
def test_a_sensor_started_after_the_leak_began_starts_at_the_pressure_left():
    """Consistency: a sensor started at 3 s on a finger leaking since 0 s reads what one started at 0 s reads then
    (noise off): PDC within 1 code from its first instant — it settles at the fluid left (settled at the full
    finger's pressure, it stepped down 80 codes and railed PAC at 0) — and PAC within 1 code from 60 ms on: PAC's
    10 Hz high-pass settles at rest, while on the falling pressure it had carried a 34-code offset, which decays."""
    t = np.array([3.0, 3.001, 3.01, 3.06, 3.1, 3.5])
    pac, pdc = ([Sensor(channels_read=["PAC", "PDC"], faults=PUNCTURE, noise=QUIET, start_s=start)
                 .sample(np.full(t.size, channel), t).astype(int) for start in (0.0, 3.0)] for channel in (PAC, PDC))
    assert np.max(np.abs(pdc[0] - pdc[1])) <= 1, pdc
    assert np.max(np.abs(pac[0] - pac[1])[3:]) <= 1, pac
    assert np.all(np.abs(pac[1] - 2048) < 60), pac  # nowhere near a rail


@pytest.mark.unit
def test_a_skin_displacement_makes_less_pressure_as_the_finger_empties():
    """Prediction: a displaced skin pushes fluid against its stiffness k_f ∝ dP/dV ∝ √V, so a 100 Hz, 2 µm
    vibration's PAC swing falls as √(V/V₀) — to 0.45 of a healthy finger's with 0.1 mL left (within 3 % + 1 code) —
    and to nothing on an emptied finger."""
    from emulator.stimuli import Vibration

    vib = [Vibration(22.0, 2.0, 2e-6, 100.0)]
    t = np.arange(23.0, 23.5, 1 / 4400.0)

    def swing(faults):
        c = Sensor(stimuli=vib, channels_read=["PAC"], faults=faults, noise=QUIET).sample(np.full(t.size, PAC), t)
        return float(np.ptp(c.astype(int)))

    healthy = swing({})
    leaking = swing({"fluid_leak_mL_per_min": 1.0, "fluid_leak_start_s": 0.0})  # 0.117 to 0.108 mL left
    gain = FluidLeak(1.0).stiffness_gain(P, 23.25)
    assert 0.44 < gain < 0.48 and healthy > 30
    assert leaking == pytest.approx(gain * healthy, rel=0.03, abs=1.0)
    assert swing(PUNCTURE) <= 1


@pytest.mark.unit
def test_before_the_leak_the_sensor_is_a_healthy_ones_to_the_bit_and_blocks_do_not_matter():
    """Consistency: noise on, the codes of PAC, PDC and E1 before the leak starts (at 1 s) are a healthy sensor's to
    the bit; after it they differ; blocks of 2 s and 37.1 ms give the same codes throughout."""
    t = np.arange(0.0, 3.0, 1 / 3000.0)
    chans = np.resize(np.array([PAC, PDC, E1]), t.size)
    stimuli = [Press(0.3, 0.5, 0.1, 0.2), Press(2.0, 0.5, 0.1, 0.2)]

    def codes(faults, block_s=2.0):
        return Sensor(stimuli=stimuli, channels_read=["PAC", "PDC", "E1"], faults=faults, seed=4,
                      block_s=block_s).sample(chans, t)

    healthy, leaking = codes({}), codes(LEAK)
    before = t < 1.0
    assert np.array_equal(healthy, codes({"fluid_leak_mL_per_min": 0.0}))  # a leak at rate 0 changes nothing
    assert np.array_equal(healthy[before], leaking[before])
    assert not np.array_equal(healthy[~before], leaking[~before])
    assert np.array_equal(leaking, codes(LEAK, block_s=0.0371))


@pytest.mark.unit
def test_the_ring_keeps_the_starting_inflations_frequency_and_decay():
    """A stated simplification (docs/model.md): the resonance and its decay are not carried with the volume — a
    sphere hitting a finger that has lost 0.1 mL rings like a full one's (within 1 %), though less strongly."""
    from bench.verification.analysis import fit_decaying_sinusoid
    from emulator.stimuli import SPHERES, sphere_drop_on

    def ring(faults):
        drop = sphere_drop_on(P, 61.5, SPHERES["5/64 in aluminum bearing"][0], 0.07, sphere="5/64 in aluminum bearing")
        t = 61.5 + np.arange(1, 500) / 8800.0
        x = Sensor(stimuli=[drop], channels_read=["PAC"], faults=faults, noise=QUIET).sample(np.full(t.size, PAC), t)
        return fit_decaying_sinusoid(t - 61.5, x.astype(float) - 2048.0)

    full, leaking = ring({}), ring(LEAK)
    assert leaking.frequency_Hz == pytest.approx(full.frequency_Hz, rel=0.01)
    assert leaking.decay_s == pytest.approx(full.decay_s, rel=0.01)
    assert leaking.amplitude < full.amplitude


@pytest.mark.unit
def test_an_emptied_finger_stays_finite_and_a_fast_leak_is_a_puncture():
    """Hard case: a punctured skin (60 mL/min, the scene format's fastest) empties the finger in half a second; every
    channel stays a finite code in range under a 3 N press and a tap after that."""
    t = np.arange(0.0, 2.0, 1 / 4400.0)
    chans = np.resize(np.array([PAC, PDC, E1, E10]), t.size)
    sensor = Sensor(stimuli=[Press(1.0, 3.0, 0.1, 0.3)], channels_read=["PAC", "PDC", "E1", "E10"],
                    faults={"fluid_leak_mL_per_min": 60.0}, seed=2)
    codes = sensor.sample(chans, t)
    assert np.all((codes >= 0) & (codes <= 4095))
    assert FluidLeak(60.0).volume_mL(0.5, 0.5) == 0.0


@pytest.mark.unit
@pytest.mark.parametrize("faults, words", [
    ({"fluid_leak_mL_per_min": -1.0}, "rate_mL_per_min = -1.0"),
    ({"fluid_leak_mL_per_min": float("nan")}, "rate_mL_per_min = nan"),
    ({"fluid_leak_mL_per_min": 1.0, "fluid_leak_start_s": -2.0}, "start_s = -2.0"),
    ({"fluid_leak_start_s": 2.0}, "fluid_leak_mL_per_min is not"),
    ({"fluid_leak_mL_per_min": True}, "rate_mL_per_min = True"),
])
def test_impossible_leaks_are_refused_by_name(faults, words):
    with pytest.raises(ValueError, match=words.replace("(", r"\(")):
        Sensor(channels_read=["PDC"], faults=faults)


SCENE = """
[scene]
name = "leak"
duration_s = 5.0
[faults]
{faults}
"""


@pytest.mark.unit
@pytest.mark.parametrize("faults, words", [
    ("fluid_leak_mL_per_min = 100.0", "faults.fluid_leak_mL_per_min = 100.0: allowed range is 0.0 to 60.0 mL/min"),
    ("fluid_leak_mL_per_min = -0.5", "allowed range is 0.0 to 60.0 mL/min"),
    ('fluid_leak_mL_per_min = "fast"', "must be a number in mL/min"),
    ("fluid_leak_start_s = 1.0", "a leak needs its rate too"),
    ("fluid_leak_mL_per_min = 1.0\nfluid_leak_start_s = 7.0", "after the end of the scene (duration_s = 5.0)"),
    ("fluid_leak_mL_per_min = 1.0\nfluid_leak_start_s = [1.0, 2.0]", "one instant (s), not a list"),
])
def test_a_scenes_leak_is_checked_naming_the_field_and_the_allowed_range(faults, words):
    with pytest.raises(SceneError) as e:
        parse_scene_text(SCENE.format(faults=faults), "leak.toml")
    assert words in str(e.value)


@pytest.mark.unit
def test_a_scenes_leak_reaches_the_sensor():
    """A scene's ``[faults]`` leak is the sensor's: the parsed faults carry it and a sensor built from them leaks."""
    scene = parse_scene_text(SCENE.format(faults="fluid_leak_mL_per_min = 2.0\nfluid_leak_start_s = 0.5"), "l.toml")
    assert scene.faults == {"fluid_leak_mL_per_min": 2.0, "fluid_leak_start_s": 0.5}
    sensor = Sensor(channels_read=["PDC"], faults=scene.faults, noise=QUIET)
    assert sensor.leak == FluidLeak(2.0, 0.5)
    c = sensor.sample(np.array([PDC, PDC]), np.array([0.1, 4.9]))
    assert c[0] - c[1] > 20

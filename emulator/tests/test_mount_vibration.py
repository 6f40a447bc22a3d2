"""Vibration through the finger's mount (a rig's stepper holding the finger, D ch. 6): white in fluid pressure, its
RMS in the PAC band as given, on from its start, the same for any block size, nothing at zero; and the texture rig
draws each trial's level from the trial's seed around the settings' median, as D saw it "not consistent from trial to
trial" — which D's roughness subtracts as the background measured before the slide."""

import numpy as np
import pytest

from emulator.channels import PAC, PDC
from emulator.conversions import PAC_PA_PER_BIT
from emulator.sensor import NoiseSources, Sensor
from emulator.stimuli import MountVibration

QUIET = NoiseSources.none()
T = np.arange(0.0, 4.0, 1 / 4400.0)


def _pac(stimuli, block_s=2.0, seed=3):
    s = Sensor(stimuli=stimuli, channels_read=["PAC"], noise=QUIET, seed=seed, block_s=block_s)
    return s.sample(np.full(T.size, PAC), T).astype(float)


@pytest.mark.unit
@pytest.mark.parametrize("rms_Pa", [0.5, 2.0, 8.0])
def test_the_pac_band_carries_the_given_rms_from_the_start_on(rms_Pa):
    """Consistency of the effect's scaling with the PAC chain: PAC reads the given RMS within 5 % (the chain's
    band edges are not brick walls), and nothing before the start."""
    x = _pac([MountVibration(1.0, rms_Pa)])
    assert np.ptp(x[(T > 0.3) & (T < 1.0)]) == 0  # noise sources off: PAC is flat before the start
    assert np.std(x[T > 1.5]) * PAC_PA_PER_BIT == pytest.approx(rms_Pa, rel=0.05)


@pytest.mark.unit
def test_two_mount_vibrations_add_in_power():
    """Consistency: two independent sources of 2 and 3 Pa read √(2² + 3²) = 3.61 Pa together (within 5 %), not the
    5 Pa of amplitudes added; each alone still reads its own level."""
    x = _pac([MountVibration(0.5, 2.0), MountVibration(1.0, 3.0)])
    assert np.std(x[(T > 0.7) & (T < 1.0)]) * PAC_PA_PER_BIT == pytest.approx(2.0, rel=0.08)
    assert np.std(x[T > 1.5]) * PAC_PA_PER_BIT == pytest.approx(np.hypot(2.0, 3.0), rel=0.05)


@pytest.mark.unit
def test_any_block_size_gives_the_same_codes_and_zero_is_nothing():
    assert np.array_equal(_pac([MountVibration(0.5, 2.0)]), _pac([MountVibration(0.5, 2.0)], block_s=0.0371))
    assert np.array_equal(_pac([MountVibration(0.5, 0.0)]), _pac([]))
    assert not np.array_equal(_pac([MountVibration(0.5, 2.0)], seed=3), _pac([MountVibration(0.5, 2.0)], seed=4))


@pytest.mark.unit
def test_it_is_vibration_not_pressure_drift():
    """White noise in the PAC band moves the averaged PDC by well under a code."""
    s = Sensor(stimuli=[MountVibration(0.0, 2.0)], channels_read=["PDC"], noise=QUIET, seed=1)
    ref = Sensor(channels_read=["PDC"], noise=QUIET, seed=1)
    t = np.linspace(0.5, 3.5, 600)
    assert abs(s.sample(np.full(t.size, PDC), t).mean() - ref.sample(np.full(t.size, PDC), t).mean()) < 1.0


@pytest.mark.unit
@pytest.mark.parametrize("bad", [-1.0, float("nan")])
def test_a_bad_level_is_refused_by_name(bad):
    with pytest.raises(ValueError, match="MountVibration.rms_Pa"):
        MountVibration(0.0, bad)


@pytest.mark.unit
def test_the_rig_draws_each_trials_stepper_level_from_its_seed():
    """Around the median with the set log spread (500 seeds: median within 6 %, log SD within 10 %); the same seed
    gives the same level; a silent stepper (the default) is 0 for every seed."""
    from bench.rigs.texture_rig import RigSettings, TextureRig

    rig = TextureRig(settings=RigSettings(stepper_noise_Pa=0.52, stepper_noise_log_spread=0.5))
    levels = np.array([rig.stepper_noise_Pa(seed) for seed in range(500)])
    assert np.median(levels) == pytest.approx(0.52, rel=0.06)
    assert np.std(np.log(levels)) == pytest.approx(0.5, rel=0.1)
    assert rig.stepper_noise_Pa(7) == rig.stepper_noise_Pa(7)
    assert TextureRig().stepper_noise_Pa(7) == 0.0


@pytest.mark.unit
def test_a_stepper_background_shows_in_the_hold_and_the_roughness_subtracts_it():
    """Prediction of D's definition: on polished aluminum (the smoothest named texture) a stepper background of
    ~1 Pa raises the hold's PAC power by about its square, yet the roughness (sliding power less the hold's) moves
    by < 0.05 ln units; with a silent stepper the trial is the default's to the bit."""
    from bench.rigs.texture_rig import Movement, RigSettings, TextureRig
    from bench.textures.library import texture
    from bench.textures.properties import properties

    move, seed = Movement(0.5, 0.025), 2

    def trial(level):
        rig = TextureRig(settings=RigSettings(stepper_noise_Pa=level), wear=False)
        return rig, rig.run_trial(texture(46), move, seed=seed)

    (_, quiet), (loud_rig, loud) = trial(0.0), trial(1.0)
    _, default = TextureRig(wear=False), TextureRig(wear=False).run_trial(texture(46), move, seed=seed)
    assert np.array_equal(quiet.recording.pac, default.recording.pac)

    def hold_power_Pa2(tr):
        r = tr.recording
        sel = (r.pac_t > r.contact_s + 0.1) & (r.pac_t < r.slide_start_s - 0.05)
        return np.var(r.pac[sel]) * PAC_PA_PER_BIT ** 2

    added = hold_power_Pa2(loud) - hold_power_Pa2(quiet)
    assert added == pytest.approx(loud_rig.stepper_noise_Pa(seed) ** 2, rel=0.3)
    assert abs(properties(loud.recording)["roughness"] - properties(quiet.recording)["roughness"]) < 0.05


@pytest.mark.unit
def test_an_experiment_sets_the_stepper_background_and_its_trials_carry_it():
    """``[rig] stepper_noise_Pa`` (and ``explore --ablation stepper-noise``) reach every trial task; a bad value is
    refused by name."""
    import dataclasses

    from bench.experiments.experiment import ExperimentError, ablated, parse_experiment
    from bench.experiments.trials import run_trial_task, sweep_tasks
    from bench.rigs.texture_rig import movement_grid

    spec = parse_experiment({"experiment": {"name": "x"}, "rig": {"stepper_noise_Pa": 0.8}})
    assert spec.stepper_noise_Pa == 0.8
    assert ablated(spec, "stepper-noise")[0].stepper_noise_Pa == 0.52
    tasks = sweep_tasks([46], [movement_grid()[7]], trials=1, movement_ids=[7], stepper_noise_Pa=spec.stepper_noise_Pa)
    assert [t.stepper_noise_Pa for t in tasks] == [0.8]
    quiet = run_trial_task(dataclasses.replace(tasks[0], stepper_noise_Pa=0.0))
    loud = run_trial_task(tasks[0])
    assert loud["roughness"] != quiet["roughness"]  # the trial ran with its stepper background
    with pytest.raises(ExperimentError, match=r"rig.stepper_noise_Pa = -1.0"):
        parse_experiment({"experiment": {"name": "x"}, "rig": {"stepper_noise_Pa": -1.0}})


@pytest.mark.unit
def test_a_trial_with_a_stepper_background_is_the_same_however_the_rig_reads_and_rewinds(monkeypatch):
    """The rig reads ahead, snapshots and rewinds while lowering; the background's random stream must be carried
    through all of it: other read chunks and look-ahead windows, or a lowering forced to run again from the start
    with snapshots, give the same trial bit for bit (over the frames both read)."""
    from bench.rigs import texture_rig
    from bench.rigs.texture_rig import Movement, RigSettings, TextureRig
    from bench.textures.library import texture

    move, noisy = Movement(0.5, 0.04), dict(stepper_noise_Pa=2.0)

    def trial(**settings):
        return TextureRig(wear=False, settings=RigSettings(**noisy, **settings)).run_trial(texture(46), move, seed=3)

    ref, other = trial(), trial(chunk_s=0.13, speculation_s=0.37)
    monkeypatch.setattr(texture_rig, "_AHEAD_FIRST_SHARE", 3.0)  # the look-ahead misjudges: lowered again
    again = trial()
    assert again.extra["lowering"]["retried"]
    for tr in (other, again):
        for name in ("pac", "pdc", "current_A"):
            x, y = getattr(ref.recording, name), getattr(tr.recording, name)
            n = min(x.size, y.size)
            assert n > 0.9 * max(x.size, y.size) and np.array_equal(x[:n], y[:n]), name
        assert tr.true_normal_N == ref.true_normal_N and tr.reached_pdc_change == ref.reached_pdc_change

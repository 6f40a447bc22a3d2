"""The rig's controller acts on D's 100 ms batches (D ch. 6: "Data was sampled continuously and transmitted back to
the computer in batches every 100ms. The digital controls for the stepper motor were also updated every 100ms").

The reference here is that controller read literally: the emulator reads one batch at a time, the controller checks
every frame of it, and gives its commands right then.  With one-frame batches it is the controller deciding after
every frame, which the rig was before batches (its codes were checked bit for bit against that version)."""

import numpy as np
import pytest

from bench.rigs import texture_rig
from bench.rigs.texture_rig import FORCE_PER_PDC_BIT_N, Movement, RigSettings, TextureRig
from bench.tests.test_texture_rig_reading import GRATING, SOFT

pytestmark = pytest.mark.unit


def _batch_by_batch(rig: TextureRig):
    """A lowering for :meth:`TextureRig._trial`: the emulator reads a batch, the controller checks each of its
    frames and gives its command at once (the lowering when the baseline's frames have all arrived, the stop when a
    frame's PDC change reaches the target)."""

    def lower(texture, movement, seed, start_position):
        s = rig.settings
        run = rig._new_run(texture, seed, start_position)
        frame_s = run.frame / run.sampler.slot_rate_Hz
        per_batch, baseline_frames = round(s.batch_s / frame_s), round(s.baseline_s / frame_s)
        target = movement.force_N / FORCE_PER_PDC_BIT_N
        while run.log.n_frames(run.frame) < baseline_frames:
            run.read_exactly(per_batch)
        baseline = np.mean(run.log.pdc_codes()[:baseline_frames])
        run.motion.move_finger(run.now, s.lower_rate_m_per_s)
        while True:
            checked = run.log.n_frames(run.frame)
            run.read_exactly(per_batch)
            change = run.log.pdc_codes()[checked:] - baseline
            if (change >= target).any():
                return run, float(change[np.argmax(change >= target)]), {}, 0

    return lower


def _same(a, b):
    """The same trial: codes, instants, currents, true force, stop frame's PDC change, phases."""
    for name in ("pac", "pac_t", "pdc", "pdc_t", "current_A", "current_t"):
        assert np.array_equal(getattr(a.recording, name), getattr(b.recording, name)), name
    assert a.true_normal_N == b.true_normal_N and a.reached_pdc_change == b.reached_pdc_change
    assert (a.recording.contact_s, a.recording.slide_start_s) == (b.recording.contact_s, b.recording.slide_start_s)


@pytest.mark.parametrize("batch_s", [0.01, 0.05, 0.1], ids=["one frame", "5 frames", "D's 100 ms"])
@pytest.mark.parametrize("texture, force", [(GRATING, 0.5), (SOFT, 1.26)], ids=["grating", "soft"])
def test_the_rig_decides_as_the_controller_reading_batch_by_batch(texture, force, batch_s):
    """(consistency) The rig's trial — read ahead in stretches, with snapshots and prediction — is the trial of the
    controller reading batch by batch, bit for bit; one-frame batches are the controller deciding after every
    frame."""
    rig = TextureRig(wear=False, settings=RigSettings(batch_s=batch_s))
    movement = Movement(force, 0.04)
    _same(rig.run_trial(texture, movement, seed=3), rig._trial(texture, movement, 3, 0, _batch_by_batch(rig)))


def test_stretches_that_end_inside_a_batch_read_on_to_its_arrival(monkeypatch):
    """(consistency) Stretches of 7 frames, read without a snapshot, against batches of 10: a stop found in a
    stretch whose batch arrives after the stretch's end is read on from there (no going back); one whose batch
    arrived before sends the lowering back to its start.  Every trial is the reference's."""
    rig = TextureRig(wear=False)
    monkeypatch.setattr(texture_rig, "_next_stretch", lambda change, target, window, read_ahead: (7, read_ahead))
    retried = []
    for seed in range(4):
        trial = rig.run_trial(GRATING, Movement(0.5, 0.04), seed=seed)
        _same(trial, rig._trial(GRATING, Movement(0.5, 0.04), seed, 0, _batch_by_batch(rig)))
        retried.append(trial.extra["lowering"]["retried"])
    assert not all(retried) and any(retried), retried  # both paths taken


def test_the_lowering_starts_when_the_baselines_last_batch_arrives():
    """A 0.15 s baseline in 0.1 s batches: the lowering command is given when the second batch arrives (0.2 s), and
    the baseline is the first 0.15 s; the trial is the reference's."""
    rig = TextureRig(wear=False, settings=RigSettings(baseline_s=0.15))
    movement = Movement(0.5, 0.04)
    trial = rig.run_trial(GRATING, movement, seed=2)
    _same(trial, rig._trial(GRATING, movement, 2, 0, _batch_by_batch(rig)))


@pytest.mark.parametrize("batch_s", [0.015, 0.0, 0.1000001])
def test_a_batch_that_is_not_a_whole_number_of_frames_is_refused_by_name(batch_s):
    with pytest.raises(ValueError, match=r"rig\.batch_s .*whole number of frames"):
        TextureRig(wear=False, settings=RigSettings(batch_s=batch_s)).run_trial(GRATING, Movement(0.5, 0.04), seed=1)


@pytest.mark.parametrize("name", ["lower_rate_m_per_s", "stage_accel_m_per_s2", "lift_rate_m_per_s", "chunk_s",
                                  "speculation_s", "pdc_average_frames"])
def test_a_zero_rate_or_length_that_the_trial_divides_by_is_refused_by_name(name):
    """Each of these divides the trial's timing: 0 passed the settings' ≥ 0 check and ended in a bare
    ZeroDivisionError (or a run that never ends); it is refused when the settings are made, naming the setting."""
    with pytest.raises(ValueError, match=rf"rig\.{name} = 0(\.0)?: .*(> 0|≥ 1)"):
        RigSettings(**{name: 0})


def test_numpy_numbers_are_settings_and_a_word_is_refused_by_name():
    """pdc_average_frames from numpy (np.int64(4)) is a whole number of frames (it was refused: only Python's int
    passed); a word for a rate is refused naming the setting (it was a bare TypeError from '<=')."""
    import numpy as np

    s = RigSettings(pdc_average_frames=np.int64(4), chunk_s=np.float64(0.25))
    assert s.pdc_average_frames == 4 and type(s.pdc_average_frames) is int
    with pytest.raises(ValueError, match=r"rig\.chunk_s = 'x': must be a number > 0"):
        RigSettings(chunk_s="x")
    with pytest.raises(ValueError, match=r"rig\.pdc_average_frames = True: a whole number"):
        RigSettings(pdc_average_frames=True)

"""How the emulator reads a rig trial ahead of the controller changes nothing the controller or the recording sees:
the same trial read in other chunks, other windows, or again after a look-ahead that overshot the stop gives the
same codes, currents and true forces, and the stop is still the first frame whose PDC change reaches the target."""

import numpy as np
import pytest

from bench.rigs import texture_rig
from bench.rigs.texture_rig import FORCE_PER_PDC_BIT_N, Movement, RigSettings, TextureRig
from emulator.texture import PeriodicComponent, Texture

pytestmark = pytest.mark.unit

# a grating with deep grooves (its relief presses in as the patch grows) and a soft abrasive
GRATING = Texture(1003, "grating", "test", rms_height_m=0.8e-6, correlation_length_m=40e-6, hurst=0.8,
                  mu_static=0.8, mu_kinetic=0.65, modulus_Pa=3.2e9, seed=5,
                  periodic=(PeriodicComponent(3e-3, 318e-6, (0.0, -0.333)),))
SOFT = Texture(1004, "soft abrasive", "test", rms_height_m=40e-6, correlation_length_m=200e-6, hurst=0.8,
               mu_static=1.0, mu_kinetic=0.8, modulus_Pa=2e6, seed=9)


def _same(a, b):
    """The same trial; the recording of the one read in shorter chunks after the stop may end earlier (it reads whole
    chunks until the trial's end), so the common part is compared."""
    for name in ("pac", "pac_t", "pdc", "pdc_t", "current_A", "current_t"):
        x, y = getattr(a.recording, name), getattr(b.recording, name)
        n = min(x.size, y.size)
        assert n > 0.9 * max(x.size, y.size) and np.array_equal(x[:n], y[:n]), name
    assert a.true_normal_N == b.true_normal_N and a.reached_pdc_change == b.reached_pdc_change


@pytest.mark.parametrize("texture, force", [(GRATING, 0.5), (SOFT, 1.26)], ids=["grating", "soft"])
def test_a_trial_does_not_depend_on_how_it_is_read_ahead(texture, force, monkeypatch):
    movement = Movement(force, 0.04)
    ref = TextureRig(wear=False).run_trial(texture, movement, seed=3)
    assert not ref.extra["lowering"]["retried"]
    other = TextureRig(wear=False, settings=RigSettings(chunk_s=0.13, speculation_s=0.37)).run_trial(
        texture, movement, seed=3)
    _same(ref, other)
    # a first stretch far past the stop: the look-ahead overshoots, the lowering runs again with snapshots
    monkeypatch.setattr(texture_rig, "_AHEAD_FIRST_SHARE", 3.0)
    again = TextureRig(wear=False).run_trial(texture, movement, seed=3)
    assert again.extra["lowering"]["retried"]
    _same(ref, again)


@pytest.mark.parametrize("batch_s", [0.01, 0.1], ids=["frame by frame", "D's 100 ms batches"])
def test_the_stepper_stops_at_the_first_frame_whose_pdc_change_reaches_the_target(batch_s):
    """The stop frame is the first whose PDC change reaches the target; the stop command is given when that frame's
    batch arrives (batches aligned to the start of sampling) and reaches the motor one latency later."""
    movement = Movement(0.5, 0.02)
    trial = TextureRig(wear=False, settings=RigSettings(batch_s=batch_s)).run_trial(GRATING, movement, seed=8)
    rec, target = trial.recording, movement.force_N / FORCE_PER_PDC_BIT_N
    change = rec.pdc.astype(float) - np.mean(rec.pdc[:20])
    stop = int(np.flatnonzero(change[20:] >= target)[0]) + 20
    assert change[stop] == trial.reached_pdc_change
    frame_s, per_batch = 0.01, round(batch_s / 0.01)
    arrival = (stop // per_batch + 1) * per_batch * frame_s
    assert rec.contact_s == pytest.approx(arrival + RigSettings().latency_s, abs=1e-9)
    if per_batch > 1:  # (this seed's stop frame is not a batch's last: the batch makes the finger go on lowering)
        assert arrival > (stop + 1) * frame_s + 0.015


def test_a_baseline_shorter_than_a_frame_is_refused_by_name():
    with pytest.raises(ValueError, match="baseline_s"):
        TextureRig(wear=False, settings=RigSettings(baseline_s=0.0)).run_trial(GRATING, Movement(0.5, 0.02), seed=1)


def test_the_lowering_with_the_baseline_read_alone_is_the_same_trial(monkeypatch):
    """No first stretch (the baseline read on its own, then windows with snapshots) reads the same trial."""
    movement = Movement(0.5, 0.04)
    ref = TextureRig(wear=False).run_trial(GRATING, movement, seed=3)
    monkeypatch.setattr(texture_rig, "_AHEAD_FIRST_SHARE", 0.0)
    alone = TextureRig(wear=False).run_trial(GRATING, movement, seed=3)
    _same(ref, alone)

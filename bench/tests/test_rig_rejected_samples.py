"""The texture rig and the samples the host flags bad (a parity error or an error word, over SPI): a fault injected
on the rig's bus (:class:`~bench.rigs.texture_rig.SpiFaultWindow`) for part of a trial.  The rig drops each bad
sample and counts it: the controller decides on the good PDC frames alone, and the recording — what the texture
properties are computed from — holds the good samples only."""

import numpy as np
import pytest

from bench.rigs.texture_rig import Movement, SpiFaultWindow, TextureRig
from bench.textures.library import texture
from bench.textures.properties import properties
from emulator.spi.model import Faults

pytestmark = pytest.mark.unit

MOVEMENT = Movement(0.5, 0.025)
SEED = 3
#: MISO's second bit inverted: the response word's bit 14, data bit 10 (+1024 codes on the resting PDC, ~735), and
#: the first byte's parity then fails, so the host flags every word of the window
FLIP = Faults(miso_flip_bit=1)


@pytest.fixture(scope="module")
def clean():
    return TextureRig(wear=False).run_trial(texture(100), MOVEMENT, seed=SEED)


def _faulted(start_s: float, end_s: float):
    return TextureRig(wear=False, spi_faults=(SpiFaultWindow(start_s, end_s, FLIP),)).run_trial(
        texture(100), MOVEMENT, seed=SEED)


def test_bad_pdc_frames_while_lowering_do_not_stop_the_finger(clean):
    """A fault while the finger is still in the air (0.25–0.35 s): the corrupted PDC readings (+1024 codes, far
    past the target) would stop the stepper in the air; rejected, the controller stops where it does without the
    fault, and the recording leaves out the 10 frames' samples and counts them (220 PAC and 10 PDC)."""
    trial = _faulted(0.25, 0.35)
    assert trial.recording.contact_s == clean.recording.contact_s
    assert trial.reached_pdc_change == clean.reached_pdc_change
    assert trial.extra["rejected_samples"]["PAC"] == {"parity error": 220}
    assert trial.extra["rejected_samples"]["PDC"] == {"parity error": 10}
    assert clean.extra["rejected_samples"] == {}
    gone = (clean.recording.pac_t >= 0.25) & (clean.recording.pac_t < 0.35 + 1e-4)
    np.testing.assert_array_equal(trial.recording.pac_t, clean.recording.pac_t[~gone])
    np.testing.assert_array_equal(trial.recording.pac, clean.recording.pac[~gone])
    assert not np.any((trial.recording.pdc_t >= 0.25) & (trial.recording.pdc_t < 0.35))


def test_bad_pac_samples_in_the_slide_leave_roughness_and_fineness_undefined_not_wrong(clean):
    """A fault during the measurement window: the PAC samples there are rejected, so the properties see a gap and
    say roughness and fineness are undefined (rather than a vibration of ±1024-code spikes); traction, the stage's
    motor current, comes not over SPI and is the same."""
    rec = clean.recording
    middle = (rec.slide_start_s + rec.slide_end_s) / 2
    trial = _faulted(middle, middle + 0.1)
    assert trial.extra["rejected_samples"]["PAC"] == {"parity error": 220}
    props = properties(trial.recording)
    assert props["traction"] == properties(rec)["traction"]
    assert props["roughness"] is None and props["fineness"] is None
    assert "gap" in props["undefined"]["roughness"] and "gap" in props["undefined"]["fineness"]


def test_a_baseline_the_host_rejected_whole_is_one_clear_error():
    with pytest.raises(ValueError, match=r"^the host rejected every PDC reading of the 20 baseline frames \(parity "
                                         r"errors or error words on the SPI bus\)"):
        _faulted(0.0, 0.25)


@pytest.mark.parametrize("window, why", [
    ((0.3, 0.2, FLIP), "0 ≤ start_s < end_s"), ((float("nan"), 0.2, FLIP), "0 ≤ start_s < end_s"),
    ((0.1, 0.2, "flip"), "an emulator.spi.model.Faults")])
def test_a_fault_window_that_is_no_window_is_refused(window, why):
    with pytest.raises(ValueError, match=why):
        SpiFaultWindow(*window)

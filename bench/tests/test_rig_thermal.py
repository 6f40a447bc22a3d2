"""The texture rig's finger exchanges heat with the texture it touches: TDC and TAC of a rig trial (the default
frame, read over SPI) fall on glass, hardly on foam, and not at all before the finger reaches the surface."""

import numpy as np
import pytest

from bench.rigs import texture_rig
from bench.rigs.texture_rig import Movement, TextureRig
from bench.textures.library import texture
from emulator import channels as ch

pytestmark = pytest.mark.unit


@pytest.fixture
def rig_trial(monkeypatch):
    """Run a trial and return (trial, its log's times, channels, codes and true normal load per frame)."""
    logs = []
    recording = texture_rig._Log.recording

    def keep(log, *args, **kwargs):
        logs.append(log)
        return recording(log, *args, **kwargs)

    monkeypatch.setattr(texture_rig._Log, "recording", keep)

    def run(texture_name: str, seed: int = 2):
        trial = TextureRig(wear=False).run_trial(texture(texture_name), Movement(1.0, 0.02), seed=seed)
        log = logs[-1]
        t, c, code = log._cat()
        return trial, t, c, code.astype(float), np.concatenate(log.cur_t), np.concatenate(log.load_N)

    return run


def test_a_rig_trial_on_glass_cools_the_finger_more_than_on_foam(rig_trial):
    """Glass (effusivity ~1.6 kW·s^½/m²K) draws heat from the skin far faster than polystyrene foam (~0.04): over
    the last second of the slide TAC sits several counts below its level before contact and TDC has fallen."""
    drops = {}
    for name in ("float glass", "polystyrene foam"):
        trial, t, c, code, _, _ = rig_trial(name)
        rec = trial.recording
        above = t < 0.5  # the finger starts 0.2 mm above and is lowered at 0.5 mm/s from 0.2 s
        late = (t > rec.slide_end_s - 1.0) & (t < rec.slide_end_s)
        drops[name] = {k: code[above & (c == k)].mean() - code[late & (c == k)].mean() for k in (ch.TAC, ch.TDC)}
    glass, foam = drops["float glass"], drops["polystyrene foam"]
    assert glass[ch.TAC] > 4.0 and abs(foam[ch.TAC]) < 1.0, drops
    assert glass[ch.TAC] > foam[ch.TAC] + 3.0, drops
    assert glass[ch.TDC] > foam[ch.TDC] + 0.25, drops


def test_nothing_thermal_happens_before_the_finger_reaches_the_surface(rig_trial):
    """Same seed on glass and on foam: every frame before the finger touches (true load still zero) is the same
    code for code — TDC and TAC included — and the thermal channels part only after."""
    runs = [rig_trial(name, seed=4) for name in ("float glass", "polystyrene foam")]
    before, after = [], []
    for _, t, c, code, load_t, load in runs:
        touch = load_t[np.flatnonzero(load > 0)[0] - 1]  # the last frame with no load: the touch comes after it
        before.append(code[t < touch])
        after.append(code[(t >= touch) & (c == ch.TAC)][:300])  # the first 3 s of contact
    assert before[0].size == before[1].size > 50 * 44  # frames of 44 conversions: over half a second
    np.testing.assert_array_equal(before[0], before[1])
    assert np.mean(after[1]) - np.mean(after[0]) > 0.4  # TAC counts: glass starts pulling TAC down, foam hardly

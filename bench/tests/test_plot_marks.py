"""The traces' drawing helpers, checked on what they hand to matplotlib: the smoothed mean of a resting channel
(the mean of the bins within reach, fewer at the ends: a level stays level up to the last point, a ramp keeps its
slope), and the stimulus markers of a run that ended early (nothing drawn past its end)."""

from __future__ import annotations

import numpy as np
import pytest

from bench.reporting import plots
from emulator.stimuli import Press, Tap, Vibration

pytestmark = pytest.mark.unit


def test_a_smoothed_level_stays_level_at_both_ends():
    for n in (3, 10, 24, 25, 26, 1000):
        x = np.full(n, 7.25)
        y = plots._smoothed(x)
        assert y.shape == x.shape and np.allclose(y, 7.25, rtol=0, atol=1e-12), n  # no dip toward 0 at the ends


def test_the_smoothed_mean_averages_the_25_bins_around_each_point_and_fewer_at_the_ends():
    x = np.arange(200.0) ** 2 / 100.0  # curved: a window that is not the centred 25 bins would show
    y = plots._smoothed(x)
    assert y.shape == x.shape
    for i in (0, 1, 5, 12, 13, 100, 186, 187, 198, 199):
        lo, hi = max(0, i - 12), min(x.size, i + 13)  # 12 bins either side, cut at the ends
        assert y[i] == pytest.approx(x[lo:hi].mean(), rel=1e-12), i
    assert y[0] == pytest.approx(x[:13].mean()) and y[-1] == pytest.approx(x[-13:].mean())
    ramp = np.linspace(-3.0, 5.0, 400)
    assert np.allclose(plots._smoothed(ramp)[12:-12], ramp[12:-12], atol=1e-12)  # a line keeps its place


def test_two_points_are_drawn_as_they_are():
    assert list(plots._smoothed(np.array([1.0, 5.0]))) == [1.0, 5.0]


class _Axes:
    def __init__(self):
        self.spans, self.lines = [], []

    def axvspan(self, x0, x1, **kw):
        self.spans.append((x0, x1))

    def axvline(self, x, **kw):
        self.lines.append(x)


def test_an_interrupted_runs_markers_stop_at_its_end():
    stimuli = [Press(0.2, 1.0, 0.1, 1.0), Vibration(0.5, 2.0, 1e-6, 100.0), Tap(0.7, 1.0, 0.01),
               Tap(0.81, 1.0, 0.01), Press(0.9, 1.0, 0.1, 0.1), Vibration(3.0, 0.2, 1e-6, 100.0)]
    ax = _Axes()
    plots._mark_stimuli(ax, stimuli, 0.8)  # the run stopped at 0.8 s
    assert ax.spans == [(0.2, 0.8), (0.5, 0.8)]  # cut at the run's end, not at the stimuli's
    assert ax.lines == [0.7]  # the tap after the end is not marked
    ax = _Axes()
    plots._mark_stimuli(ax, stimuli[:1], 10.0)
    assert ax.spans == [(0.2, stimuli[0].end_s)]  # a finished run: the whole press


def test_the_traces_mark_the_stimuli_up_to_the_simulated_end_not_the_scenes(monkeypatch, tmp_path):
    from bench.reporting.report import baselines
    from bench.running.runner import run_scene
    from bench.scenes.scene import parse_scene_text

    rec = run_scene(parse_scene_text('[scene]\nname = "cut"\nduration_s = 0.4\n'
                                     '[[stimulus]]\nkind = "tap"\nat_s = 0.1\npeak_N = 0.5\n'), progress=False)
    rec.simulated_s = 0.25  # as a run stopped at 0.25 s records it
    ends = []
    monkeypatch.setattr(plots, "_mark_stimuli", lambda ax, stimuli, t_max: ends.append(t_max))
    dict(plots.scene_plots(rec, baselines(rec)))["traces.png"](tmp_path / "traces.png")
    assert ends and set(ends) == {0.25}

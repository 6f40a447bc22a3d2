"""Sliding trials inside a scene run: each slide's PAC and PDC codes as the host read them, its stage current
(from the contact's tangential force through the stage's motor model, :mod:`bench.textures.stage`), and its texture properties.

The runner hands every chunk to :meth:`SlideRecorder.add`; only samples inside a slide's window are kept, so
memory grows with the slides' total duration, not the scene's.  :meth:`SlideRecorder.finish` returns one row per
slide (texture, movement, the skin it met, the true forces, traction, roughness, fineness) and its force log.
"""

from __future__ import annotations

import numpy as np

from bench.textures.stage import StageMotor
from bench.textures.properties import TrialRecording, measurement_window, properties
from emulator.effects import effect_rng
from emulator.sliding import Slide

LEAD_S = 0.1  # samples kept before each slide's contact (s)


class SlideRecorder:
    def __init__(self, scene, motor: StageMotor | None = None):
        self.scene = scene
        self.slides = sorted((s for s in scene.stimuli if isinstance(s, Slide)), key=lambda s: s.start_s)
        self.motor = motor or StageMotor()
        self._parts = [{"PAC": [], "PDC": []} for _ in self.slides]

    def __bool__(self) -> bool:
        return bool(self.slides)

    def add(self, parts: dict) -> None:
        for k, s in enumerate(self.slides):
            for ch in ("PAC", "PDC"):
                if ch not in parts:
                    continue
                t, code, status = parts[ch]
                if not len(t) or t[-1] < s.start_s - LEAD_S or t[0] > s.end_s:
                    continue
                sel = (t >= s.start_s - LEAD_S) & (t <= s.end_s) & (status == 0)
                if sel.any():
                    self._parts[k][ch].append((t[sel], code[sel]))

    def finish(self, sensor) -> list[dict]:
        """One row per slide that the run reached (SI units; properties as in bench.textures.properties)."""
        effect = next((e for e in sensor.graph.effects if e.name == "sliding_contact"), None) if sensor else None
        rows = []
        for k, s in enumerate(self.slides):
            got = {ch: [np.concatenate(x) for x in zip(*self._parts[k][ch])] if self._parts[k][ch] else None
                   for ch in ("PAC", "PDC")}
            if effect is None or got["PAC"] is None or got["PDC"] is None or got["PAC"][0][-1] < s.slide_end_s:
                continue  # the run ended (or was interrupted) before this slide did
            log = effect.force_log(k)
            current = self.motor.current_A(log["stage_N"], effect_rng(self.scene.seed, f"slide[{k}].motor_current"))
            rec = TrialRecording(got["PAC"][0], got["PAC"][1], got["PDC"][0], got["PDC"][1], log["t"], current,
                                 s.start_s + s.approach_s, s.slide_start_s, s.slide_end_s, texture=s.texture.number,
                                 force_N=s.force_N, velocity_m_s=s.velocity_m_per_s, trial=k, seed=self.scene.seed)
            sliding = (log["t"] > s.slide_start_s + s.accel_s) & (log["t"] < s.slide_end_s - s.accel_s)
            if not sliding.any():  # no cruise (the ramps meet, distance = velocity × accel_s): the forces' mean over
                # the window the properties are measured in, which validation keeps ≥ 2 log samples long (the
                # cruise's empty mean had gone into record.json as NaN)
                first, last = measurement_window(rec)
                sliding = (log["t"] >= first) & (log["t"] <= last)
            skin = self.scene.trial_skins[k] if k < len(self.scene.trial_skins) else {}
            row = {"trial": k, "start_s": s.start_s, "texture": s.texture.number, "texture_name": s.texture.name,
                   "force_N": s.force_N, "velocity_m_per_s": s.velocity_m_per_s, "distance_m": s.distance_m,
                   "skin_serial": skin.get("serial"), "ridge_height_m": skin.get("ridge_height_m"),
                   "true_normal_N": float(np.mean(log["normal_N"][sliding])) if sliding.any() else float("nan"),
                   "mean_tangential_N": float(np.mean(log["tangential_N"][sliding])) if sliding.any() else float("nan")}
            # a property this trial's codes leave undefined (a PAC constant over the window, as with every noise
            # source off, has no spectral centroid) is null, and why: the run and the other slides' rows stand
            row.update(properties(rec))
            rows.append(row)
        return rows

    def force_traces(self, sensor) -> dict[str, np.ndarray]:
        """All slides' force logs joined in time order (for plots)."""
        effect = next((e for e in sensor.graph.effects if e.name == "sliding_contact"), None) if sensor else None
        if effect is None:
            return {}
        logs = [effect.force_log(k) for k in range(len(self.slides))]
        return {key: np.concatenate([lg[key] for lg in logs]) for key in logs[0]} if logs else {}

"""Plots people would rather look at than read: channel traces and the PAC spectrogram."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy import signal  # noqa: E402

from emulator.stimuli import AmbientStep, PowerOn, Press, PressureCalibrator, SphereDrop, Tap, Touch, Vibration  # noqa: E402,E501


def _mark_stimuli(ax, stimuli, t_max):
    for s in stimuli:
        if s.start_s > t_max:
            continue
        color = {SphereDrop: "tab:red", Tap: "tab:orange", Press: "tab:green", Touch: "tab:green",
                 Vibration: "tab:purple", PressureCalibrator: "tab:brown", PowerOn: "tab:gray",
                 AmbientStep: "tab:cyan"}[type(s)]
        if isinstance(s, (Press, Vibration, PressureCalibrator)):
            ax.axvspan(s.start_s, min(s.end_s, t_max), color=color, alpha=0.08, lw=0)
        else:
            ax.axvline(s.start_s, color=color, alpha=0.35, lw=0.8)


def scene_plots(rec, phys: dict, out_dir: Path) -> list[str]:
    written = []
    panels = [(k, lbl) for k, lbl in (("PAC_Pa", "PAC vibration (Pa)"), ("PDC_kPa", "PDC pressure change (kPa)"),
                                      ("TDC_C", "TDC temperature (°C)"), ("TAC_C_per_s", "TAC (°C/s)"),
                                      ("E_kohm", "electrode impedance (kΩ)"))
              if k in phys or (k == "E_kohm" and "E1_ohm" in phys)]
    if panels:
        fig, axes = plt.subplots(len(panels), 1, figsize=(11, 3.2 * len(panels)), sharex=True, squeeze=False)
        for ax, (key, label) in zip(axes[:, 0], panels):
            if key == "E_kohm":
                for n in range(1, 20):
                    if f"E{n}_ohm" in phys:
                        ax.plot(rec.channels[f"E{n}"].times, phys[f"E{n}_ohm"] / 1e3, lw=0.7, label=f"E{n}")
                ax.legend(ncol=10, fontsize=6, loc="upper right")
            else:
                ch = key.split("_")[0]
                ax.plot(rec.channels[ch].times, phys[key], lw=0.5, color="black")
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
            _mark_stimuli(ax, rec.scene.stimuli, rec.simulated_s)
        axes[-1, 0].set_xlabel("time (s)")
        axes[0, 0].set_title(f"{rec.scene.name}: channel traces (markers: stimuli)")
        fig.tight_layout()
        fig.savefig(out_dir / "traces.png", dpi=110)
        plt.close(fig)
        written.append("traces.png")
    if "PAC_Pa" in phys and phys["PAC_Pa"].size > 256:
        t = rec.channels["PAC"].times
        fs = 1.0 / np.median(np.diff(t))
        nper = max(32, int(round(0.08 * fs)))  # 80 ms window, as D ch. 3
        f, tt, sxx = signal.spectrogram(phys["PAC_Pa"], fs=fs, nperseg=nper, noverlap=nper // 2, scaling="density")
        fig, ax = plt.subplots(figsize=(11, 4))
        mesh = ax.pcolormesh(tt + t[0], f, 10 * np.log10(np.maximum(sxx, 1e-12)), shading="auto", cmap="magma")
        fig.colorbar(mesh, ax=ax, label="PAC PSD (dB re 1 Pa²/Hz)")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("frequency (Hz)")
        ax.set_title(f"{rec.scene.name}: PAC spectrogram (80 ms windows)")
        fig.tight_layout()
        fig.savefig(out_dir / "spectrogram.png", dpi=110)
        plt.close(fig)
        written.append("spectrogram.png")
    if "E1_ohm" in phys and any(isinstance(s, Touch) for s in rec.scene.stimuli):
        written.append(electrode_map(rec, phys, out_dir))
    return written


def electrode_map(rec, phys: dict, out_dir: Path) -> str:
    """The finger's core unwrapped (along the finger × around it) with each electrode coloured by its largest
    impedance change over the scene, and the touches marked."""
    from emulator.electrodes import CORE_RADIUS_MM, electrode_positions_mm

    pos = electrode_positions_mm()
    arc = CORE_RADIUS_MM * np.arctan2(pos[:, 1], -pos[:, 2])  # mm around the finger from the ventral midline
    change = []
    for n in range(1, 20):
        z = phys[f"E{n}_ohm"]
        rest = np.median(z[: max(5, len(z) // 20)])
        change.append(100 * np.max(np.abs(z - rest)) / rest)
    fig, ax = plt.subplots(figsize=(8, 4.2))
    ax.add_patch(plt.Rectangle((-16, -np.pi * CORE_RADIUS_MM / 1.6), 21, 2 * np.pi * CORE_RADIUS_MM / 1.6,
                               fill=False, ls="--", color="gray"))
    sc = ax.scatter(pos[:, 0], arc, c=change, s=260, cmap="viridis", edgecolors="black")
    for n, (x, a) in enumerate(zip(pos[:, 0], arc), start=1):
        ax.annotate(f"E{n}", (x, a), ha="center", va="center", fontsize=7, color="white")
    for s in rec.scene.stimuli:
        if isinstance(s, Touch):
            if s.electrode:
                k = int(s.electrode[1:]) - 1
                x, a = pos[k, 0], arc[k]
            else:
                x, a = s.x_mm, CORE_RADIUS_MM * np.radians(s.angle_deg)
            ax.plot(x, a, "x", color="red", ms=10, mew=2)
    fig.colorbar(sc, ax=ax, label="largest impedance change (%)")
    ax.set_xlabel("along the finger, x (mm; tip at right)")
    ax.set_ylabel("around the finger from the ventral midline (mm)")
    ax.set_title(f"{rec.scene.name}: electrode map (red ×: touches)")
    ax.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(out_dir / "electrode_map.png", dpi=110)
    plt.close(fig)
    return "electrode_map.png"


def sensitivity_plot(claims, out_dir: Path) -> Path:
    """d_min versus frequency for the sensor, with the human threshold curve (D Fig. 5-4)."""
    from bench.verification.psychophysics import human_threshold_m

    d = next(c.details["d_min_m"] for c in claims if "d_min_m" in c.details)
    f = np.array(sorted(d))
    dm = np.array([d[x] for x in f])
    ff = np.geomspace(10, 900, 200)
    out_dir.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.loglog(ff, human_threshold_m(ff) * 1e6, color="tab:green", label="human threshold (after Verrillo 1963)")
    ax.loglog(f, dm * 1e6, "o-", color="tab:red", label="emulated BioTac d_min (D eq. 5.3)")
    ax.set_xlabel("vibration frequency (Hz)")
    ax.set_ylabel("minimum detectable amplitude (µm)")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    ax.set_title("Frequency sensitivity (D Fig. 5-4)")
    fig.tight_layout()
    path = out_dir / "frequency_sensitivity.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path

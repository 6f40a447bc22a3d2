"""Plots people would rather look at than read: channel traces and the PAC spectrogram.

Scene plots are drawn from the run's streaming summary (min/max envelopes of at most one bin per pixel column,
a spectrogram of bounded size), so drawing them costs the same memory after ten hours as after a minute.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.patches import Rectangle

from bench.reporting.figures import figure_file
from emulator.stimuli import (AmbientStep, PowerOn, Press, PressureCalibrator, SphereDrop, Tap, Touch, Vibration,
                              contact_place)


def _mark_stimuli(ax, stimuli, t_max):
    for s in stimuli:
        if s.start_s > t_max:
            continue
        color = {SphereDrop: "tab:red", Tap: "tab:orange", Press: "tab:green", Touch: "tab:green",
                 Vibration: "tab:purple", PressureCalibrator: "tab:brown", PowerOn: "tab:gray",
                 AmbientStep: "tab:cyan"}.get(type(s), "tab:gray")
        if isinstance(s, (Press, Vibration, PressureCalibrator)):
            ax.axvspan(s.start_s, min(s.end_s, t_max), color=color, alpha=0.08, lw=0)
        else:
            ax.axvline(s.start_s, color=color, alpha=0.35, lw=0.8)


def electrodes_read(names) -> list[str]:
    """The electrodes among the channel names ``names`` (E1..E24, in order): those a run's frame sampled, E1 or not."""
    return [f"E{n}" for n in range(1, 25) if f"E{n}" in names]


#: a channel whose codes stay within this many codes, top to bottom, over the whole run is at rest: its noise is
#: the ADC's (±1–2 LSB), drawn as a band around its mean instead of a zig-zag that fills the panel like a barcode
QUIET_SPAN_CODES = 5


def at_rest(summary, channel: str) -> bool:
    """Whether ``channel``'s good samples stayed within :data:`QUIET_SPAN_CODES` codes over the whole run."""
    _, lo, hi, _ = summary.channels[channel].envelope()
    return bool(lo.size) and hi.max() - lo.min() <= QUIET_SPAN_CODES


def _envelope_panel(summary, key: str, base: dict):
    """(centre instants, low, high, mean) of one trace panel in physical units, from the streamed min/max envelope
    (one bin per pixel column at most: the zig-zag low → high → low draws what the full trace would)."""
    from emulator import conversions as conv

    ch = key.split("_")[0]
    c, lo, hi, mean = summary.channels[ch].envelope()
    if ch == "PAC":
        f = lambda x: conv.pac_to_pa(x, base["PAC"])  # noqa: E731
    elif ch == "PDC":
        f = lambda x: conv.pdc_to_kpa(x, base["PDC"])  # noqa: E731
    elif ch == "TDC":
        f = conv.tdc_to_celsius
    elif ch == "TAC":
        tc, _, _, tmean = summary.channels["TDC"].envelope()
        tdc = np.interp(c, tc, tmean) if tc.size else np.full(c.size, np.nan)
        f = lambda x: conv.tac_to_celsius_per_s(x, tdc, base["TAC"])  # noqa: E731
    else:
        f = lambda x: conv.impedance_ohm(x) / 1e3  # noqa: E731
    a, b = f(lo), f(hi)
    return c, np.minimum(a, b), np.maximum(a, b), f(mean)


def _trace(ax, summary, key: str, base: dict, color: str = "black", lw: float = 0.5) -> None:
    """One channel's trace: its zig-zag envelope, or — PAC aside, whose noise is the signal — its mean within a
    min–max band when the channel stayed at rest (:func:`at_rest`; a note says so)."""
    c, lo, hi, mean = _envelope_panel(summary, key, base)
    channel = key.split("_")[0]
    if channel == "PAC" or not at_rest(summary, channel):
        _zigzag(ax, c, lo, hi, lw=lw, color=color)
        return
    ax.axhspan(lo.min(), hi.max(), color=color, alpha=0.12, lw=0)
    ax.plot(c, _smoothed(mean), lw=1.0, color=color)
    ax.text(0.01, 0.96, f"at rest throughout: the band spans the lowest to the highest code read (ADC noise, within "
                        f"{QUIET_SPAN_CODES} codes); the line is the mean, smoothed over "
                        f"{100 * SMOOTH_BINS / max(c.size, 1):.2g} % of the run",
            transform=ax.transAxes, fontsize=7, va="top", color="0.3")


#: envelope bins a resting channel's mean is averaged over (of at most 1000 across the run)
SMOOTH_BINS = 25


def _smoothed(x: np.ndarray) -> np.ndarray:
    """``x`` averaged over :data:`SMOOTH_BINS` neighbouring bins (fewer at the ends)."""
    if x.size < 3:
        return x
    k = min(SMOOTH_BINS, x.size)
    window = np.ones(k)
    return np.convolve(x, window, "same") / np.convolve(np.ones(x.size), window, "same")


#: envelope bins per piece of a traced line: Agg rasterizes each piece on its own, and a zig-zag spanning the panel's
#: height at every pixel column, drawn as one path, holds megabytes of coverage cells while it is rasterized
ZIGZAG_PIECE_BINS = 250


def _zigzag(ax, c, lo, hi, **kw):
    """The envelope as the full trace would look: low → high in each bin, on to the next bin's low; drawn in pieces
    of :data:`ZIGZAG_PIECE_BINS` bins, each starting where the last ended (one colour, one legend entry)."""
    x, y = np.repeat(c, 2), np.column_stack([lo, hi]).ravel()
    step = 2 * ZIGZAG_PIECE_BINS
    for start in range(0, max(x.size - 1, 1), step):
        line, = ax.plot(x[start:start + step + 1], y[start:start + step + 1], **kw)
        kw = {**kw, "color": line.get_color(), "label": "_nolegend_"}


def _nearest_cells(ax, x, y, values, **kw):
    """``ax.pcolormesh(x, y, values, shading="nearest")`` drawn as an image: each pixel takes the value of the
    nearest (x, y) centre and the axes end half a spacing beyond the outer centres, as pcolormesh draws it, in the
    memory of the figure's pixels instead of one polygon per cell (a 1000-column spectrogram: ~4 MB less)."""
    from matplotlib.image import NonUniformImage

    (x0, x1), (y0, y1) = (_outer_edges(np.asarray(c, float)) for c in (x, y))
    image = NonUniformImage(ax, interpolation="nearest", extent=(x0, x1, y0, y1), **kw)
    image.set_data(x, y, values)
    ax.add_image(image)
    image.sticky_edges.x[:], image.sticky_edges.y[:] = [x0, x1], [y0, y1]
    ax.update_datalim([(x0, y0), (x1, y1)])
    ax.autoscale_view()
    return image


def _outer_edges(centres: np.ndarray) -> tuple[float, float]:
    """The outer edges of cells centred on ``centres`` (ascending): half a spacing beyond the first and the last."""
    if centres.size < 2:
        return float(centres[0]), float(centres[0])
    return float(centres[0] - (centres[1] - centres[0]) / 2), float(centres[-1] + (centres[-1] - centres[-2]) / 2)


def scene_plots(rec, base: dict) -> list[tuple[str, object]]:
    """The plots of a run, drawn from its streaming summary (memory independent of the run's length): a list
    of (file name, draw(path)) — each draw writes one PNG to ``path``."""
    summary = rec.summary
    names = summary.channels
    plots = []
    panels = [(k, lbl) for k, lbl, need in (("PAC_Pa", "PAC vibration (Pa)", ("PAC",)),
                                            ("PDC_kPa", "PDC pressure change (kPa)", ("PDC",)),
                                            ("TDC_C", "TDC temperature (°C)", ("TDC",)),
                                            ("TAC_C_per_s", "TAC (°C/s)", ("TAC", "TDC")))
              if all(n in names for n in need)]
    if electrodes_read(names):
        panels.append(("E_kohm", "electrode impedance (kΩ)"))

    def traces(path: Path):
        size = (11, 3.2 * len(panels))
        with figure_file(path, len(panels), 1, figsize=size, sharex=True, squeeze=False) as (_, axes):
            for ax, (key, label) in zip(axes[:, 0], panels):
                if key == "E_kohm":
                    electrodes = electrodes_read(names)
                    resting = [e for e in electrodes if at_rest(summary, e)]
                    for e in electrodes:
                        c, lo, hi, mean = _envelope_panel(summary, f"{e}_ohm", base)
                        if e in resting:  # a grey mean line each (their levels differ from unit to unit)
                            ax.plot(c, _smoothed(mean), lw=0.8, color="0.55", label="_nolegend_")
                        else:
                            _zigzag(ax, c, lo, hi, lw=0.7, label=e)
                    if resting:
                        ax.plot([], [], color="0.55", label=f"{len(resting)} at rest: "
                                + (f"{resting[0]}..{resting[-1]}" if len(resting) == len(electrodes) else
                                   ", ".join(resting)) + " (smoothed mean)")
                    ax.legend(ncol=10 if len(resting) < len(electrodes) else 1, fontsize=6, loc="upper right")
                else:
                    _trace(ax, summary, key, base)
                ax.set_ylabel(label)
                ax.grid(alpha=0.3)
                _mark_stimuli(ax, rec.scene.stimuli, rec.simulated_s)
            axes[-1, 0].set_xlabel("time (s)")
            axes[0, 0].set_title(f"{rec.scene.name}: channel traces (markers: stimuli)")

    if panels:
        plots.append(("traces.png", traces))
    spec = summary.spectrogram
    if spec is not None and spec.samples > 256 and spec.result() is not None:
        def spectrogram(path: Path):
            from emulator.conversions import PAC_PA_PER_BIT

            f, tt, sxx = spec.result()
            with figure_file(path, figsize=(11, 4)) as (fig, ax):
                psd = sxx * PAC_PA_PER_BIT ** 2  # codes²/Hz → Pa²/Hz (the offset does not enter: windows are detrended)
                image = _nearest_cells(ax, tt, f, 10 * np.log10(np.maximum(psd, 1e-12)), cmap="magma")
                fig.colorbar(image, ax=ax, label="PAC PSD (dB re 1 Pa²/Hz)")
                ax.set_xlabel("time (s)")
                ax.set_ylabel("frequency (Hz)")
                avg = f", each column the mean of {spec.group}" if spec.group > 1 else ""
                ax.set_title(f"{rec.scene.name}: PAC spectrogram (80 ms windows{avg})")

        plots.append(("spectrogram.png", spectrogram))
    if electrodes_read(names) and any(contact_place(s) is not None for s in rec.scene.stimuli):  # placed contacts
        plots.append(("electrode_map.png", lambda path: electrode_map(rec, path)))
    if getattr(rec, "forces", None) and len(rec.forces.get("t", ())):
        plots.append(("forces.png", lambda path: sliding_forces(rec, path)))
    if getattr(rec, "slides", None):
        plots.append(("properties.png", lambda path: sliding_properties(rec, path)))
    return plots


def sliding_forces(rec, path: Path) -> None:
    """Normal and tangential force on the skin and the slip velocity, at 100 Hz, over every slide."""
    f = rec.forces
    with figure_file(path, 2, 1, figsize=(11, 5.5), sharex=True) as (_, axes):
        axes[0].plot(f["t"], f["normal_N"], ".", ms=1.5, label="normal")
        axes[0].plot(f["t"], f["tangential_N"], ".", ms=1.5, label="tangential")
        axes[0].set_ylabel("force on the skin (N)")
        axes[0].legend(loc="upper right", fontsize=8)
        axes[1].plot(f["t"], 100 * f["slip_m_per_s"], ".", ms=1.5, color="tab:gray")
        axes[1].set_ylabel("slip velocity (cm/s)")
        axes[1].set_xlabel("time (s)")
        for ax in axes:
            ax.grid(alpha=0.3)
        axes[0].set_title(f"{rec.scene.name}: contact forces and slip (100 Hz)")


def sliding_properties(rec, path: Path) -> None:
    """Traction, roughness and fineness of each sliding trial, in trial order, with the skin's ridge height."""
    rows = rec.slides
    k = [r["trial"] for r in rows]
    with figure_file(path, 4, 1, figsize=(9, 8), sharex=True) as (_, axes):
        for ax, key, label in zip(axes, ("traction", "roughness", "fineness"),
                                  ("traction (A)", "roughness (ln bits²)", "fineness (ln Hz)")):
            ax.plot(k, [r[key] for r in rows], "o-", ms=4)
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        axes[3].plot(k, [1e6 * (r["ridge_height_m"] or 0.0) for r in rows], "s-", ms=3, color="tab:brown")
        axes[3].set_ylabel("ridge height (µm)")
        axes[3].set_xlabel("sliding trial")
        axes[3].grid(alpha=0.3)
        axes[0].set_title(f"{rec.scene.name}: texture properties per trial")


def electrode_map(rec, path: Path) -> None:
    """The finger's core unwrapped (along the finger × around it) with each electrode coloured by its largest
    impedance change over the scene (hollow: an electrode the host did not read), and the touches marked."""
    from bench.running.aggregate import hist_median_pair
    from emulator.conversions import impedance_ohm
    from emulator.electrodes import CORE_RADIUS_MM, electrode_positions_mm

    pos = electrode_positions_mm(rec.scene.variant)  # the sensor's own variant's table (24 on an SP)
    arc = CORE_RADIUS_MM * np.arctan2(pos[:, 1], -pos[:, 2])  # mm around the finger from the ventral midline
    change = []  # %, NaN for an electrode the host did not read (or read no good sample of): no change known
    for n in range(1, len(pos) + 1):
        cs = rec.summary.channels.get(f"E{n}")
        if cs is None or cs.good == 0:
            change.append(np.nan)
            continue
        a, b = hist_median_pair(cs.early_hist if cs.early_hist.any() else cs.hist)
        rest = float((impedance_ohm(a) + impedance_ohm(b)) / 2)  # the median of the resting impedances
        nz = np.flatnonzero(cs.hist)
        extreme = np.abs(impedance_ohm(np.array([nz[0], nz[-1]])) - rest)
        change.append(100 * float(extreme.max()) / rest)
    with figure_file(path, figsize=(6.4, 4.6)) as (fig, ax):
        ax.add_patch(Rectangle((-16, -np.pi * CORE_RADIUS_MM / 1.6), 21, 2 * np.pi * CORE_RADIUS_MM / 1.6,
                                   fill=False, ls="--", color="gray"))
        for s in rec.scene.stimuli:  # under the electrodes, so that no label is hidden
            place = contact_place(s)  # a touch, or a tap or press given a place
            if place is not None:
                electrode, x_mm, angle_deg = place
                if electrode:
                    k = int(electrode[1:]) - 1
                    x, a = pos[k, 0], arc[k]
                else:
                    x, a = x_mm, CORE_RADIUS_MM * np.radians(angle_deg)
                ax.plot(x, a, "x", color="red", ms=9, mew=2, zorder=1)
        change = np.asarray(change, float)
        read = np.isfinite(change)
        sc = ax.scatter(pos[read, 0], arc[read], c=change[read], s=300, cmap="viridis", edgecolors="black", zorder=2)
        if not read.all():  # hollow, not a colour of the scale: no change is known where nothing was read
            ax.scatter(pos[~read, 0], arc[~read], s=300, facecolors="none", edgecolors="0.6", zorder=2,
                       label="not read")
            ax.legend(loc="lower left", fontsize=7)
        shade = sc.to_rgba(np.where(read, change, 0.0))
        for n, (x, a, rgba, was_read) in enumerate(zip(pos[:, 0], arc, shade, read), start=1):
            light = not was_read or 0.299 * rgba[0] + 0.587 * rgba[1] + 0.114 * rgba[2] > 0.5  # dark text on light
            ax.annotate(f"E{n}", (x, a), ha="center", va="center", fontsize=7, zorder=3,
                        color="black" if light else "white")
        fig.colorbar(sc, ax=ax, label="largest impedance change (%)", shrink=0.8)
        ax.set_xlabel("along the finger, x (mm; tip at right)")
        ax.set_ylabel("around the finger from the ventral midline (mm)")
        ax.set_title(f"{rec.scene.name}: electrode map (red ×: touches)")
        ax.set_aspect("equal")


#: the file :func:`sensitivity_plot` writes into its folder (claims --plots)
SENSITIVITY_PLOT = "frequency_sensitivity.png"


def sensitivity_plot(claims, out_dir: Path) -> Path:
    """d_min versus frequency for the sensor, with the human threshold curve (D Fig. 5-4)."""
    from bench.verification.psychophysics import human_threshold_m

    d = next((c.details["d_min_m"] for c in claims if "d_min_m" in c.details), None)
    if d is None:
        raise ValueError("the frequency-sensitivity plot needs the vibration claims' d_min (claims --only vibration)")
    f = np.array(sorted(d))
    dm = np.array([d[x] for x in f])
    ff = np.geomspace(10, 900, 200)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / SENSITIVITY_PLOT
    with figure_file(path, figsize=(7, 4.5)) as (_, ax):
        ax.loglog(ff, human_threshold_m(ff) * 1e6, color="tab:green",
                  label="human threshold (Bolanowski et al. 1988, thenar)")
        ax.loglog(f, dm * 1e6, "o-", color="tab:red", label="emulated BioTac d_min (D eq. 5.3)")
        ax.set_xlabel("vibration frequency (Hz)")
        ax.set_ylabel("minimum detectable amplitude (µm)")
        ax.grid(alpha=0.3, which="both")
        ax.legend()
        ax.set_title("Frequency sensitivity (D Fig. 5-4)")
    return path

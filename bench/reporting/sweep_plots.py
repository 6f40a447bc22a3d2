"""Plots of a texture sweep: each property against force and velocity, one panel per property, a line per
texture and velocity (the 6 × 6 movement grid of D eqs 6.20–6.21)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.ticker import NullFormatter

from bench.reporting.figures import figure_file

PROPERTIES = (("traction", "traction (A)"), ("roughness", "roughness (ln bits²)"), ("fineness", "fineness (ln Hz)"))


def properties_vs_movement(cols: dict[str, np.ndarray], names: dict[int, str], path: Path) -> Path:
    """Mean ± SD of each property over repetitions, against force (one line per velocity) and against velocity
    (one line per force), for each texture; written to ``path`` (PNG)."""
    textures = sorted(set(cols["texture"].tolist()))
    path.parent.mkdir(parents=True, exist_ok=True)
    with figure_file(path, len(PROPERTIES), 2, figsize=(11, 3.2 * len(PROPERTIES)), squeeze=False) as (_, axes):
        _draw_properties(axes, cols, names, textures)
    return path


def _draw_properties(axes, cols: dict[str, np.ndarray], names: dict[int, str], textures: list[int]) -> None:
    """One panel per property and axis (force, velocity): a line per texture and the other axis's value."""
    cmap = colormaps["tab10"]
    for r, (key, label) in enumerate(PROPERTIES):
        for c, (x_key, line_key, x_label, x_scale) in enumerate((
                ("force_N", "velocity_m_per_s", "normal force (N)", 1.0),
                ("velocity_m_per_s", "force_N", "velocity (cm/s)", 100.0))):
            ax = axes[r][c]
            for k, tex in enumerate(textures):
                sel_t = cols["texture"] == tex
                lines = sorted(set(cols[line_key][sel_t].round(6).tolist()))
                for j, lv in enumerate(lines):
                    sel = sel_t & np.isclose(cols[line_key], lv)
                    xs = sorted(set(cols[x_key][sel].round(6).tolist()))
                    mean = [cols[key][sel & np.isclose(cols[x_key], x)].mean() for x in xs]
                    sd = [cols[key][sel & np.isclose(cols[x_key], x)].std() for x in xs]
                    ax.errorbar(np.multiply(xs, x_scale), mean, yerr=sd, color=cmap(k % 10), alpha=0.35 + 0.65 * (j + 1) / len(lines),
                                lw=1, capsize=2, label=names.get(tex, str(tex)) if j == len(lines) - 1 else None)
            ax.set_xscale("log")
            # the grid's own values as plain-number ticks (log-axis defaults overlap as 2×10⁻¹, 3×10⁻¹, …)
            grid = sorted(set((cols[x_key] * x_scale).round(6).tolist()))
            ax.set_xticks(grid, [f"{x:.3g}" for x in grid])
            ax.xaxis.set_minor_formatter(NullFormatter())
            ax.set_xlabel(x_label)
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=7, ncol=2)
    axes[0][0].set_title("against force (shade: velocity)")
    axes[0][1].set_title("against velocity (shade: force)")

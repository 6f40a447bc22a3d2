"""One way to make a PNG figure: ``with figure_file(path, rows, cols, figsize=…) as (fig, axes): draw``.

matplotlib runs headless (Agg); the file is laid out, written whole under a temporary name and moved into place
only when drawing finished (bench.atomic), and the figure is closed whatever happens, so a failed or interrupted
plot leaves neither a half-written PNG nor an open figure behind.

Memory (plots are drawn at the end of a run, where its peak falls): the figure is made at :data:`DPI`, so laying
it out and saving it share one Agg canvas; and the garbage of earlier figures — a closed figure is a reference
cycle through its canvas, axes and texts, which hold the canvas's pixels — is collected before a new one is made.
"""

from __future__ import annotations

import contextlib
import gc
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from bench.atomic import atomic_write  # noqa: E402

#: resolution of every PNG the bench writes (dots per inch)
DPI = 110


@contextlib.contextmanager
def figure_file(path, *subplots_args, **subplots_kw):
    """``plt.subplots(*subplots_args, **subplots_kw)`` as ``(fig, axes)``; on leaving the block without an error the
    figure is laid out and saved to ``path`` (PNG, :data:`DPI`); the figure is always closed."""
    gc.collect()  # earlier figures' canvases (closed, but cyclic garbage) go before this one's is allocated
    fig, axes = plt.subplots(*subplots_args, dpi=DPI, **subplots_kw)
    try:
        yield fig, axes
        fig.tight_layout()
        with atomic_write(Path(path)) as tmp:
            fig.savefig(tmp, dpi=DPI, format="png")
    finally:
        plt.close(fig)

"""Where the bench finds its shipped files (fixtures, firmware sources) and writes build products (``out/``)."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
FIXTURES = REPO / "fixtures"
SCENES_DIR = FIXTURES / "scenes"
OUT = REPO / "out"

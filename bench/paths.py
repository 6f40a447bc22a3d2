"""Where the bench finds its shipped files (fixtures, firmware sources) and writes build products (``out/``)."""

from __future__ import annotations

from pathlib import Path

from bench.tomlfile import spelled

REPO = Path(__file__).resolve().parent.parent
FIXTURES = REPO / "fixtures"
SCENES_DIR = FIXTURES / "scenes"
OUT = REPO / "out"


def folder_name_problem(name, field: str) -> str | None:
    """Why ``name`` (the value of ``field``, e.g. "scene.name") cannot name a default out folder, or None: it must be
    1 to 100 ASCII letters, digits, '-', '_' or '.', and not '.' or '..' — a name, never a path."""
    if name is None:
        return f"{field} is missing: a name of 1 to 100 ASCII letters, digits, '-', '_' or '.'"
    if not isinstance(name, str) or not name:
        return f"{field} = {spelled(name)}: must be a non-empty string"
    if len(name) > 100 or name in (".", "..") or not all(ch.isascii() and (ch.isalnum() or ch in "-_.") for ch in name):
        return (f"{field} = {spelled(name)}: must be a name, not a path (it names the default out folder): 1 to 100 "
                f"ASCII letters, digits, '-', '_' or '.', and not '.' or '..'")
    return None

"""Where the bench finds its shipped files (fixtures, firmware sources) and writes build products (``out/``)."""

from __future__ import annotations

from pathlib import Path

from bench.tomlfile import spelled

REPO = Path(__file__).resolve().parent.parent
FIXTURES = REPO / "fixtures"
SCENES_DIR = FIXTURES / "scenes"
OUT = REPO / "out"
#: Files the bench reads from its source tree while it runs (scene and sensor data, the firmware, the RTL, the
#: Cheetah library's C): a copy of the packages installed without them (a plain ``pip install``, which takes the
#: Python files only) cannot run, so the command line and the pytest plugin refuse it by name
#: (:func:`source_tree_problem`).
SOURCE_FILES = ("fixtures/electrodes.csv", "firmware_tests/firmware/bt_bridge.c", "emulator/rtl/biotac_spi.v",
                "emulator/cheetah/cheetah_emu.c")


def source_tree_problem() -> str | None:
    """Why this copy of the bench cannot run (it lacks files of its source tree: :data:`SOURCE_FILES`), or None."""
    missing = [f for f in SOURCE_FILES if not (REPO / f).is_file()]
    if not missing:
        return None
    return (f"this copy of biotac-bench ({REPO}) lacks {', '.join(missing)}: it reads its source tree while it runs, "
            f"so it runs from a clone only — install the clone with 'pip install -e /path/to/biotac-bench' (as "
            f"./scripts/setup does) or use the clone's .venv (README, Set-up)")


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

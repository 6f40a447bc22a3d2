"""trials.json: the machine-readable trial table that ``texture-sweep`` and ``explore`` both write beside trials.csv,
in one schema, and its reader.

The file is one JSON object (standard JSON: a non-finite number is null)::

    {"format": "biotac-bench trials",   # TRIALS_FORMAT: what the file is
     "version": 1,                      # TRIALS_VERSION: its layout; a reader refuses a version it does not know
     "command": "texture-sweep",        # or "explore": what wrote it
     "library": {"path": ..., "sha256": ..., "shipped": ...},   # the texture library the trials slid on
     "wall_s": 12.3,                    # wall-clock time (s) the rows took (explore: its pilot, training and
                                        # validation stages, a cached stage ~0)
     "workers": "LocalCluster, 2 worker(s)",   # where they ran
     "rows": [{...}, ...]}              # one object per trial: the rows of trials.csv, same fields, same order

A row's fields are those of :func:`bench.experiments.trials.run_trial_task`'s rows (SI units: ``force_N``,
``velocity_m_per_s``, ``traction`` in A, ``roughness`` ln bits², ``fineness`` ln Hz, ...); trials.csv holds the same
rows as text, a None as an empty cell and an object (a row's ``undefined``, {property: why}) as its JSON text.
:func:`read_trials` reads a file back and checks the envelope, naming the file and the field in one line (a value
shown as every message shows one: :func:`bench.tomlfile.spelled`).
"""

from __future__ import annotations

import json
from pathlib import Path

from bench.cli.args import strict_json
from bench.errors import BenchError, escaped
from bench.tomlfile import spelled

TRIALS_FORMAT = "biotac-bench trials"
TRIALS_VERSION = 1
#: the commands that write trials.json
TRIALS_COMMANDS = ("texture-sweep", "explore")
#: the envelope's fields, in the order written: the JSON types a reader accepts, and those in words
TRIALS_FIELDS = {"format": ((str,), "text"), "version": ((int,), "a whole number"), "command": ((str,), "text"),
                 "library": ((dict,), "an object"), "wall_s": ((int, float), "a number"),
                 "workers": ((str,), "text"), "rows": ((list,), "a list")}


class TrialsFileError(BenchError, ValueError):
    """A trials.json that cannot be read as the schema of :mod:`bench.reporting.trials_file`."""


def trials_json(command: str, rows: list[dict], library: dict, wall_s: float, workers: str) -> str:
    """The text of trials.json for ``rows`` (one dict per trial) that ``command`` ran on the texture library
    ``library`` (:meth:`bench.textures.library.LibraryFile.record`) in ``wall_s`` s on ``workers``."""
    if command not in TRIALS_COMMANDS:
        raise ValueError(f"command {spelled(command)}: trials.json is written by {', '.join(TRIALS_COMMANDS)}")
    return strict_json({"format": TRIALS_FORMAT, "version": TRIALS_VERSION, "command": command, "library": library,
                        "wall_s": wall_s, "workers": workers, "rows": rows}, indent=1)


def read_trials(path: str | Path) -> dict:
    """The trials.json at ``path`` as a dict (the envelope's fields and ``rows``, a list of dicts), after checking
    that it is one: :class:`TrialsFileError`, one line naming the file and the field, otherwise."""
    where = escaped(str(path))
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as e:
        raise TrialsFileError(f"{where}: cannot be read ({e.strerror or e})") from None
    except (UnicodeDecodeError, ValueError) as e:
        raise TrialsFileError(f"{where}: not JSON ({e})") from None
    if not isinstance(doc, dict) or "format" not in doc:
        raise TrialsFileError(f"{where}: no \"format\" field: not a trials.json of this schema (one written before "
                              f"it had one is a bare list or lacks the field; its rows are in trials.csv beside it)")
    if doc["format"] != TRIALS_FORMAT:
        raise TrialsFileError(f"{where}: format = {spelled(doc['format'])}: expected \"{TRIALS_FORMAT}\"")
    if doc.get("version") != TRIALS_VERSION:
        raise TrialsFileError(f"{where}: version = {spelled(doc.get('version'))}: this biotac-bench reads "
                              f"version {TRIALS_VERSION}")
    for key, (types, kind) in TRIALS_FIELDS.items():
        value = doc.get(key)
        if key not in doc or isinstance(value, bool) or not isinstance(value, types):
            shown = f"{key} = {spelled(value)}" if key in doc else f"{key} is missing"
            raise TrialsFileError(f"{where}: {shown}: must be {kind}")
    if doc["command"] not in TRIALS_COMMANDS:
        raise TrialsFileError(f"{where}: command = {spelled(doc['command'])}: one of "
                              f"{', '.join(TRIALS_COMMANDS)}")
    bad = next((i for i, r in enumerate(doc["rows"]) if not isinstance(r, dict)), None)
    if bad is not None:
        raise TrialsFileError(f"{where}: rows[{bad}] = {spelled(doc['rows'][bad])}: must be an object (one "
                              f"trial)")
    return doc

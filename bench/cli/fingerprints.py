"""``python -m bench.verification.benchmark OUT.json [OLD.json]``: the scenes' code fingerprints written to OUT.json
under the lock beside it, compared with another tree's; ``--write-fixture`` and ``--write-fidelity-errors`` rewrite
the committed fixtures (:mod:`bench.verification.benchmark` measures; this is its command line)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from bench.cli.args import say_leftovers
from bench.errors import escaped
from bench.reporting.outdir import OutDirError, OutFile
from bench.verification import benchmark as B


def main(argv) -> int:
    """``python -m bench.verification.benchmark OUT.json [OLD.json]``: write the fingerprints; with OLD.json (another
    tree's), list the runs whose codes differ and exit 1 if any does.  ``--write-fixture``: rewrite
    :data:`~bench.verification.benchmark.SCENE_FINGERPRINT_FIXTURE` instead (``--write-fidelity-errors``:
    :data:`~bench.verification.benchmark.FIDELITY_ERROR_FIXTURE`).  OUT.json is locked from start to end
    (:class:`~bench.reporting.outdir.OutFile`: ``.<name>.lock`` beside it): a second command writing the same file
    is refused at once, exit status 2, naming the first's pid — rather than both computing it and the last to finish
    silently replacing the other's, perhaps from another tree — and the temporary files of one killed as it wrote
    are removed and named.  (The committed fixtures are not locked: two rewrites of one tree's fixture write the
    same codes.  The per-effect cost table is ``biotac-bench benchmark --effects``.)"""
    ap = argparse.ArgumentParser(description=B.scene_code_fingerprints.__doc__)
    ap.add_argument("out", type=Path, nargs="?", metavar="OUT.json",
                    help="where to write the fingerprints (an earlier file there is replaced; a second command "
                         "writing the same file meanwhile is refused)")
    ap.add_argument("against", type=Path, nargs="?", metavar="OLD.json")
    ap.add_argument("--scenes", type=Path, default=B.SCENES_DIR)
    ap.add_argument("--write-fixture", action="store_true",
                    help="rewrite the committed fingerprints of the scenes that do not slide (fixtures/fingerprints/"
                         "scenes_default.json) and nothing else; only for an intended change of their codes")
    ap.add_argument("--write-fidelity-errors", action="store_true",
                    help="rewrite the committed errors of the fidelity profiles (fixtures/fidelity/errors.json) and "
                         "nothing else; only for an intended change of a profile's error")
    ap.add_argument("--remake", action="append", metavar="SCENE",
                    help="with --write-fidelity-errors: measure only this shipped scene (its file name without "
                         ".toml; repeatable) and keep the others' errors and provenance")
    a = ap.parse_args(argv)
    if a.remake and not a.write_fidelity_errors:
        ap.error("--remake goes with --write-fidelity-errors")
    if a.write_fidelity_errors:
        if a.write_fixture or a.out is not None or a.scenes != B.SCENES_DIR:
            ap.error("--write-fidelity-errors takes no other option or file (it measures the shipped scenes)")
        try:
            doc = B.write_fidelity_error_fixture(remake=a.remake)
        except ValueError as e:
            ap.error(str(e))
        remade = len(doc["scenes"]) if a.remake is None else len(set(a.remake))
        print(f"wrote {B.FIDELITY_ERROR_FIXTURE}: {remade} of {len(doc['scenes'])} scenes measured")
        return 0
    if a.write_fixture:
        if a.out is not None or a.scenes != B.SCENES_DIR:
            ap.error("--write-fixture takes no OUT.json, OLD.json or --scenes (it fingerprints the shipped scenes)")
        doc = B.write_scene_fingerprint_fixture()
        print(f"wrote {B.SCENE_FINGERPRINT_FIXTURE}: {len(doc['scenes'])} scenes "
              f"({', '.join(doc['scenes'])})")
        return 0
    if a.out is None:
        ap.error("OUT.json is required (or --write-fixture)")
    try:
        out = say_leftovers(OutFile.open(a.out, "OUT.json", "fingerprint run", "this file"))
    except OutDirError as e:
        ap.exit(2, f"error: {e}\n")
    with out:
        return _write_fingerprints(ap, a)


def _write_fingerprints(ap, a) -> int:
    """The fingerprints written to OUT.json (and compared with OLD.json) once :func:`main` holds the
    lock beside it (``a``: its arguments)."""
    prints = B.scene_code_fingerprints(a.scenes)
    try:
        B.write_json(a.out, prints)
    except OSError as e:
        ap.exit(2, f"error: OUT.json {escaped(str(a.out))}: not written ({e.strerror or e}); an earlier file there is "
                   f"left as it was\n")
    if a.against is None:
        return 0
    try:
        old = json.loads(a.against.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        ap.exit(2, f"error: OLD.json {escaped(str(a.against))}: cannot be read as JSON "
                   f"({getattr(e, 'strerror', None) or e})\n")
    if not isinstance(old, dict):
        ap.exit(2, f"error: OLD.json {escaped(str(a.against))}: not fingerprints (a JSON object of run -> "
                   f"fingerprint)\n")
    differ = sorted(k for k in set(old) | set(prints) if old.get(k) != prints.get(k))
    for k in differ:
        print(f"DIFFERENT {k}: {old.get(k)} -> {prints.get(k)}")
    print(f"{len(prints)} runs, {len(differ)} with different codes")
    return 1 if differ else 0

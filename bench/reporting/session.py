"""One run into one out folder, as ``biotac-bench run`` does it: nothing lost, nothing mixed, nothing wedged.

1. The out folder is checked, created and locked before anything runs (:mod:`bench.reporting.outdir`).
2. The scene streams into ``samples.h5`` under a temporary name while SIGINT/SIGTERM only ask to stop at the
   next chunk (:mod:`bench.running.signals`); memory holds the streaming summary, not the samples.
3. Exports, plots, then ``samples.h5``, ``report.md`` and ``record.json`` are renamed into place
   (:func:`bench.reporting.report.write_outputs`), all of them also after a signal that stopped the simulation;
   only a signal arriving while they are written stops exports and plots.  The record's status is ``ok``,
   ``failed`` (with the error) or ``interrupted`` (with the signal).  A several-sensor run writes sensors
   2..N into ``sensor<k>/`` first, in the same guarded, locked phase (each gets its record.json), and sensor 1's
   record, written last, lists their status.

Exit status follows the record: 0 ok, 1 failed, 128 + the signal's number when interrupted (130 SIGINT, 143
SIGTERM) — also when the signal came only after the record was written ("ok": the run is complete, and says so).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
from dataclasses import dataclass, field
from pathlib import Path

from bench.atomic import save_in_temp_folder
from bench.reporting.outdir import RUN_SENSOR, OutFolder, fresh_folder
from bench.reporting.report import write_outputs
from bench.reporting.store import SampleStore, os_reason, write_recording
from bench.running.runner import Recording, read_channel_names, run_scene
from bench.running.signals import StopSignals


@dataclass
class RunResult:
    record: dict
    exit_code: int
    folder: Path
    recording: Recording
    sensor_records: dict[int, dict] = field(default_factory=dict)  # sensors 2..N: number -> its record.json
    late_signal: str | None = None  # a signal that came after the record was written: the run is complete


def run_to_folder(scene, out=None, *, force: bool = False, csv: bool = False, npz: bool | None = None,
                  plots: bool = True, progress: bool = True, compression: str = "gzip",
                  chunk_s: float = 4.0, out_root: Path = Path("out")) -> RunResult:
    """Run ``scene`` into ``out`` (a path: checked, locked, refused when not empty unless ``force``; or an open
    :class:`OutFolder`), or, without ``out``, into a fresh folder ``out_root/<scene name>[-n]``."""
    if isinstance(out, OutFolder):
        folder = out
    elif out is not None:
        folder = OutFolder.open(out, force=force)
    else:
        folder = fresh_folder(Path(out_root) / scene.name, force=force)
    with StopSignals() as guard:  # held until the folder is closed: a signal after the record can't cut the tidy-up
        try:
            names = read_channel_names(scene)
            h5 = folder.temp_path("samples.h5")
            store = SampleStore(h5, scene, names, compression)
            try:
                rec = run_scene(scene, progress=progress, chunk_s=chunk_s, keep_samples=False, sinks=[store],
                                should_stop=guard.should_stop)
            except BaseException:
                store.abort()
                raise
            guard.begin_writing()  # a signal from now on stops exports and plots; one before it only the simulation
            earlier = None if store.failed else rec.error  # the run's own failure (a NaN at the ADC): kept
            if not store.failed:
                with contextlib.suppress(Exception):  # (a failure sets store.failed: the samples are kept below)
                    store.close("running", rec.simulated_s, rec.error)
            if store.failed:
                h5 = _keep_what_was_streamed(store, h5, rec, folder, compression)
                rec.error = "; ".join(filter(None, [earlier, rec.error]))
            if guard.signum is not None and rec.status == "ok":
                rec.status = "interrupted"
            sensor_records = {k: _write_sensor(sub, folder, k, guard=guard, csv=csv, plots=plots, npz=npz,
                                               compression=compression)
                              for k, sub in sorted(rec.sensors.items())}
            record = write_outputs(rec, folder, csv=csv, plots=plots, npz=npz, samples_tmp=h5, guard=guard,
                                   sensors=sensor_records)
            code = {"ok": 0, "interrupted": guard.exit_code or 130}.get(record["status"], 1)
            if h5 is not None and "samples.h5" in record["outputs"]:
                from bench.reporting.store import StoredChannels

                rec.channels = StoredChannels(folder.path / "samples.h5")
        finally:
            folder.remove_temps()
            folder.close()
    late = guard.signal_name if guard.signum is not None and record["status"] == "ok" else None
    return RunResult(record, guard.exit_code if late else code, folder.path, rec, sensor_records, late)


def _keep_what_was_streamed(store: SampleStore, h5: Path, rec: Recording, folder: OutFolder,
                            compression: str) -> Path | None:
    """The stream into ``samples.h5`` failed (a full disk) and ended the run: read back every sample it took before
    ``rec.simulated_s``, delete the broken file (which frees its space) and write those samples into a fresh one —
    in the system's temporary folder when the out folder has no room for it.  Returns the fresh file in the out
    folder, or None; ``rec.error`` says where the samples are, or that they are lost."""
    at = f"writing samples.h5 at {rec.simulated_s:.3f} s: {store.failed}"
    rec.status = "failed"
    try:
        kept = store.salvage(rec.simulated_s)
    except Exception as e:
        kept, lost = None, os_reason(e)
    finally:
        store.abort()
        with contextlib.suppress(OSError):
            os.unlink(h5)
    recorded = f"the {rec.simulated_s:.3f} s recorded before it"
    if kept is not None:
        salvaged = dataclasses.replace(rec, channels=kept)
        fresh = folder.temp_path("samples.h5")
        try:
            write_recording(fresh, salvaged, compression)
            rec.error = f"{at}; samples.h5 holds {recorded}"
            return fresh
        except Exception:
            with contextlib.suppress(OSError):
                os.unlink(fresh)
        try:
            saved = save_in_temp_folder(lambda path: write_recording(path, salvaged, compression),
                                        "biotac-samples-", ".h5")
            rec.error = f"{at}; {recorded} were saved as {saved} (no room for them in {folder.path})"
            return None
        except Exception as e:
            lost = os_reason(e)
    rec.error = f"{at}; {recorded} could not be kept ({lost}): they are lost"
    return None


def _write_sensor(sub: Recording, folder: OutFolder, k: int, **kw) -> dict:
    """Sensor ``k``'s outputs into ``folder``/sensor<k>/ (its own lock, taken while ``folder``'s is held), under
    the run's signal guard (in ``kw``): its record, or — if even the folder cannot be used — a failed stand-in."""
    try:
        with OutFolder.open(folder.path / f"sensor{k}", flag=folder.flag, kind=RUN_SENSOR,
                            default=folder.default) as sub_folder:
            return write_outputs(sub, sub_folder, sensor_index=k, **kw)
    except Exception as e:
        return {"status": "failed", "error": f"{type(e).__name__}: {e}", "outputs": []}

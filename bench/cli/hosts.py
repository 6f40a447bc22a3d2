"""Host-stack commands: the bridge firmware on a pty, recording a bridge's serial stream. Bad values are refused
by argparse with one line naming the flag and exit status 2, before anything runs (:mod:`bench.cli.args`)."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from pathlib import Path

from bench.cli.args import (NotedWhenTyped, Terminated, any_seed, firmware_choice, firmware_file, number,
                            output_file, say_leftovers, sigterm_raises, stimuli_count, typed, whole)
from bench.errors import BenchError, OutputNotWritten, escaped
from bench.running.signals import signals_deferred
from bench.tomlfile import spelled


# --- bridge ------------------------------------------------------------------------------------------------------


def bridge_scene_kw(scene, n_sensors: int | None = None, seed: int | None = None, spi: str | None = None) -> dict:
    """:class:`~bench.hosts.bridge.FirmwareBench`'s keywords for the bridge firmware on ``scene``'s sensors:
    ``n_sensors`` (None: the scene's count; fewer are refused), ``sensors``
    (:func:`~bench.hosts.scene_sensors.sensors_from_scene`: units, variants, parameters, faults, noise, fidelity,
    stimuli), ``pattern`` (from host.sequence), ``spi`` (given, else host.spi) and ``seed`` (given, else the
    scene's).  :class:`~bench.errors.SceneError` for what the firmware cannot do."""
    from bench.hosts.scene_sensors import firmware_pattern, sensors_from_scene

    n_sensors = scene.n_sensors if n_sensors is None else n_sensors
    return {"n_sensors": n_sensors, "sensors": sensors_from_scene(scene, n_sensors, seed=seed),
            "pattern": firmware_pattern(scene), "spi": spi or scene.spi, "seed": scene.seed if seed is None else seed}


def _cmd_bridge(a) -> int:
    import time

    from bench.hosts.bridge import FirmwareBench

    if a.scene:
        from bench.scenes.scene import load_scene

        scene = load_scene(a.scene)
        kw = bridge_scene_kw(scene, a.sensors, a.seed, a.spi)
        faults = "; ".join(f"sensor {k}: " + (", ".join(f"{n}={v}" for n, v in scene.sensor_spec(k).faults.items())
                                              or "none") for k in range(1, kw["n_sensors"] + 1))
        feels = "; ".join(f"sensor {k} feels {stimuli_count(len(scene.sensor_spec(k).stimuli))}"
                          for k in range(1, scene.n_sensors + 1))
        what = (f"{kw['n_sensors']} emulated sensor(s) built from scene '{scene.name}' (units, parameters, noise, "
                f"fidelity {scene.fidelity}, seed {kw['seed']}; {feels}; faults — {faults})")
    else:
        kw = {"n_sensors": a.sensors or 1, "seed": 0 if a.seed is None else a.seed, "spi": a.spi or "software"}
        what = f"{kw['n_sensors']} emulated sensor(s) at rest (seed {kw['seed']}: sensor k draws {kw['seed']} + k - 1)"
    with sigterm_raises():
        try:
            fb = FirmwareBench(realtime=not a.fast, speed=a.speed, baudrate=a.baud, rx_buffer=a.rx_buffer,
                               firmware=firmware_choice(a.firmware, "bridge"), **kw).start()
        except KeyboardInterrupt as e:  # the first start builds the firmware (and the RTL): seconds to minutes
            name, status = ("SIGTERM", 143) if isinstance(e, Terminated) else ("SIGINT", 130)
            print(f"{name} while the bridge was starting (building the firmware"
                  f"{' and the RTL' if kw['spi'] == 'rtl' else ''}): no port was opened", file=sys.stderr)
            return status
        try:
            print(f"{'your firmware (' + ', '.join(a.firmware) + ')' if a.firmware else 'bridge firmware'} running "
                  f"with {what}", flush=True)
            print(f"serial port: {fb.port}", flush=True)
            print(f"UART {a.baud} baud, host receive buffer {a.rx_buffer} bytes"
                  + (" (a host that stops reading loses what does not fit, as on a real UART)" if not a.fast else
                     " (unpaced: the firmware waits for a reading host)"), flush=True)
            print("open it with any serial program (raw, no flow control); Ctrl-C or SIGTERM to stop", flush=True)
            deadline = None if a.seconds is None else time.monotonic() + a.seconds
            while (deadline is None or time.monotonic() < deadline) and fb._thread.is_alive():
                time.sleep(0.2)
        except KeyboardInterrupt:
            pass
        finally:
            with signals_deferred():
                try:
                    fb.stop()
                except RuntimeError as e:
                    print(f"error: {e}", file=sys.stderr)
                    return 1
        print(f"stopped at virtual time {fb.virtual_time:.2f} s; bytes lost to overruns: {fb.link.bytes_overrun}")
    return 0


# --- record ------------------------------------------------------------------------------------------------------

END_STATUS = {"complete": 0, "stream stopped": 1, "disconnected": 1, "port error": 1, "interrupted": 130,
              "terminated": 143}


def recording_file(text: str) -> str:
    """argparse type of record's --out: a file to write (:func:`output_file`); a folder — an existing one, or a
    path ending in "/" — is refused with the file name to give instead (a path ending in "/" would otherwise be
    written as a file named like the folder)."""
    if text.endswith(("/", os.sep)) or Path(text).is_dir():
        raise argparse.ArgumentTypeError(f"{text}: is a folder; give the file to write, e.g. "
                                         f"{Path(text) / 'recording.npz'}")
    return output_file(text)


#: The first line of the CSV ``record --csv`` writes; a file beside --out is only ever replaced if it starts so.
RECORDING_CSV_HEADER = "seq,slot,channel,sensor,code,status"


def _csv_beside(out: Path) -> Path:
    """Where ``record --csv`` writes the CSV: beside the NPZ, same name, suffix .csv."""
    return out.with_suffix(".csv")


def _is_recording_csv(path: Path) -> bool:
    """Whether ``path`` is a regular file (not a symbolic link) whose first line is :data:`RECORDING_CSV_HEADER`."""
    from bench.atomic import read_head

    head = read_head(path, len(RECORDING_CSV_HEADER) + 2)
    return head is not None and head.splitlines()[:1] == [RECORDING_CSV_HEADER.encode()]


def _is_recording_npz(path: Path) -> bool:
    """Whether ``path`` is a regular file (not a symbolic link) holding a recording: an NPZ with its codes and
    layout arrays."""
    import zipfile

    from bench.atomic import open_regular

    try:
        fh = open_regular(path)
        if fh is None:
            return False
        with fh, zipfile.ZipFile(fh) as z:
            return {"codes.npy", "layout.npy"} <= set(z.namelist())
    except (OSError, zipfile.BadZipFile):
        return False


def _out_named(out: Path, where: str | None) -> str:
    """How record's messages name --out: ``where`` (:func:`~bench.reporting.outdir.folder_named`: the flag and the
    path, or the default file), or, None, ``--out PATH``."""
    from bench.reporting.outdir import folder_named

    return where or folder_named(out, "--out", what="file")


def _refuse_overwriting(out: Path, csv: bool, force: bool, where: str | None = None) -> None:
    """Before the port is opened: an earlier recording at ``out`` (named ``where``: :func:`_out_named`) or a CSV
    beside it (which would no longer match the NPZ) is refused unless ``force``; a --out that the CSV would
    overwrite is refused always."""
    where = _out_named(out, where)
    if csv and _csv_beside(out) == out:
        raise BenchError(f"{where}: the CSV is written beside the NPZ with the suffix .csv, i.e. over it; "
                         f"give the NPZ's name (e.g. {escaped(str(out.with_suffix('.npz')))})")
    present = [p for p in (out, _csv_beside(out)) if p.exists() or p.is_symlink()]
    folders = [p for p in present if p.is_dir()]
    if folders:
        raise BenchError(f"{where}: {escaped(str(folders[0]))} is a folder, where the recording's CSV would go; give "
                         f"another --out")
    if present and not force:
        raise BenchError(f"{where}: {_paths_said(present)} already there (an earlier recording?); "
                         f"give another --out, or --force to replace {'it' if len(present) == 1 else 'them'}")
    if out in present and not out.is_symlink() and not _is_recording_npz(out):  # a link is replaced, not followed
        raise BenchError(f"{where}: already there and not a recording (an NPZ with codes and layout); --force "
                         f"replaces only an earlier recording: move it away, or give another --out")
    csv_path = _csv_beside(out)
    if csv_path in present and not _is_recording_csv(csv_path):
        raise BenchError(f"{where}: {escaped(str(csv_path))} is not a recording's CSV (its first line is not "
                         f"{spelled(RECORDING_CSV_HEADER)}); --force replaces only an earlier recording: move it away, "
                         f"or give another --out")


def _save_recording(out: Path, frames, meta: dict, csv: bool, force: bool = True,
                    where: str | None = None) -> tuple[list[Path], dict]:
    """Write the frames to ``out`` (NPZ; named ``where`` in messages, :func:`_out_named`) and, with ``csv``, beside
    it (CSV: channels by name); returns the files written and {file: why} for a CSV that could not be (the NPZ
    holds every sample, so it is placed all the same).

    Atomic: every file is written whole under a temporary name first (:func:`bench.atomic.temp_path`), then put in
    place by :func:`_place_recording` (replacing an earlier recording only with ``force``).  An NPZ that cannot be
    written (a full disk) goes to the system's temporary folder instead, and :class:`~bench.errors.OutputNotWritten` says
    where: a live stream cannot be recorded again."""
    import numpy as np

    from emulator.channels import variant

    n = len(frames)
    shapes = {(tuple(f.channels), f.sensor_mask) for f in frames}
    if len({(len(c), m) for c, m in shapes}) == 1:
        layout = "compact"  # codes[frame, slot, k]: the k-th present sensor
        codes = np.stack([f.codes for f in frames])
        status = np.stack([f.status for f in frames])
        channels = np.stack([f.channels for f in frames])
    else:  # the pattern or the set of sensors changed: index by sensor number, pad with status 255
        layout = "by_sensor"  # codes[frame, slot, sensor - 1]
        slots = max(len(f.channels) for f in frames)
        codes = np.zeros((n, slots, 5), np.uint16)
        status = np.full((n, slots, 5), 255, np.uint8)
        channels = np.full((n, slots), 255, np.int64)
        for i, f in enumerate(frames):
            k = len(f.channels)
            channels[i, :k] = f.channels
            for j, s in enumerate(f.sensors):
                codes[i, :k, s - 1] = f.codes[:, j]
                status[i, :k, s - 1] = f.status[:, j]
    arrays = dict(seq=np.array([f.seq for f in frames]), mask=np.array([f.sensor_mask for f in frames]),
                  channels=channels, codes=codes, status=status, layout=np.array(layout),
                  **{k: np.array(v) for k, v in meta.items()})
    name_of = variant("biotac-sp").channel_name  # every variant's channel indices, E1..E24

    def write_npz(fh):
        np.savez_compressed(fh, **arrays)

    def write_csv(fh):
        fh.write((RECORDING_CSV_HEADER + "\n").encode())
        for f in frames:
            fh.write("".join(f"{f.seq},{k},{name_of.get(int(ch), ch)},{s},{f.codes[k, j]},{f.status[k, j]}\n"
                             for k, ch in enumerate(f.channels) for j, s in enumerate(f.sensors)).encode())

    from bench.atomic import written_temp

    temps: dict[Path, Path] = {}
    try:
        out.parent.mkdir(parents=True, exist_ok=True)  # (a full disk may refuse even the folder)
        temps[out] = written_temp(out, write_npz)
    except OSError as e:  # a stream cannot be recorded again: the NPZ goes where there is room, and says so
        raise OutputNotWritten(f"{_out_named(out, where)}: the recording could not be written "
                               f"({e.strerror or e}); " + _rescue(write_npz)) from None
    not_written = {}
    if csv:
        try:
            temps[_csv_beside(out)] = written_temp(_csv_beside(out), write_csv)
        except OSError as e:  # the NPZ holds every sample: it is placed, and the CSV's absence said
            not_written[_csv_beside(out)] = e.strerror or str(e)
        except BaseException:  # anything else: no temporary file left behind unnamed
            temps[out].unlink(missing_ok=True)
            raise
    _place_recording(out, temps, _csv_beside(out) in temps, force, where)  # refused or failed: kept, and named
    return list(temps), not_written


def _rescue(write) -> str:
    """Write a recording that could not go where it was asked into the system's temporary folder; the sentence that
    says where it is (or that it could not be kept)."""
    import tempfile

    from bench.atomic import save_in_temp_folder

    def write_file(path: Path) -> None:
        with open(path, "wb") as fh:
            write(fh)

    try:
        path = save_in_temp_folder(write_file, "biotac-recording-", ".npz")
    except OSError as e:
        return f"nor in {escaped(tempfile.gettempdir())} ({e.strerror or e}): the recording is lost"
    return f"it was saved as {escaped(str(path))} instead"


def _place_recording(out: Path, temps: dict[Path, Path], csv: bool, force: bool, where: str | None = None) -> None:
    """Move a finished recording's temporary files (``temps``: final name -> temporary file) into place.

    Without ``force`` nothing is replaced: the files take their names only where nothing is there, all or none
    (:func:`bench.atomic.commit_new`: a hard link, so even a file that appears at the last moment is never
    replaced), and a CSV beside ``out`` that would not match it is refused too: whatever appeared there during the
    recording (:func:`_refuse_overwriting` found nothing at the start) is refused.  With ``force`` the replaced
    recording's CSV beside ``out`` is removed (it would not match) and the files replace an earlier recording
    (:func:`bench.atomic.commit`), never a file that is not a recording's, come meanwhile.  Refused or failed, the
    recording is kept beside ``out`` under names of its own (:func:`_keep_aside`), which the BenchError names."""
    import errno

    from bench.atomic import commit, commit_new

    beside = _csv_beside(out)
    beside_taken = beside.exists() or beside.is_symlink()
    try:
        if force:
            if csv and beside_taken and not _is_recording_csv(beside):
                raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), str(beside))
            if out.exists() and not out.is_symlink() and not _is_recording_npz(out):
                raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), str(out))
            if _is_recording_csv(beside):
                beside.unlink()  # the replaced recording's CSV, or the one rewritten below
            for path, tmp in temps.items():
                commit(tmp, path)
        else:
            if not csv and beside_taken:  # a CSV that would not match this NPZ (with --csv commit_new refuses it)
                raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), str(beside))
            commit_new(temps)
    except OSError as e:
        if isinstance(e, FileExistsError):
            why = (f"{escaped(str(e.filename))} appeared during the recording (written by another program?) and is "
                   f"not replaced" + ("" if force else " without --force"))
        else:
            why = f"cannot put the recording in place: {escaped(str(e))}"
        raise BenchError(f"{_out_named(out, where)}: {why}; "
                         f"the recording is kept as {_keep_aside(temps)} (rename it to use "
                         f"it)") from None


def _keep_aside(temps: dict[Path, Path]) -> str:
    """Give a finished recording that cannot take its place (``temps``: final name -> temporary file) names of its
    own beside it, ``NAME.kept-<8 random hex digits>.npz`` (and ``.csv``, the same digits), so that it is never
    taken for what an interrupted record left (:class:`~bench.reporting.outdir.OutFile` removes those); replacing
    nothing (:func:`bench.atomic.commit_new`: a hard link, or a copy on a file system without them; either
    failing otherwise — a full disk refusing the copy —, a rename to the fresh random name).  If nothing can name it
    there, the last resort is a copy elsewhere (:func:`_copy_aside`).
    Where the files are, as a message names them (:func:`~bench.errors.escaped`)."""
    import secrets

    from bench.atomic import commit_new

    at = {final: tmp for final, tmp in temps.items() if tmp.exists()}  # final name -> where its data is now
    for _ in range(5):
        digits = secrets.token_hex(4)
        aside = {final.with_name(f"{final.stem}.kept-{digits}{final.suffix}"): final for final in at}
        try:
            return _paths_said(commit_new({kept: at[final] for kept, final in aside.items()}))
        except FileExistsError:
            continue  # (8 random digits taken: another draw)
        except OSError:  # neither a link nor a copy: a rename, to a name nothing holds
            if any(os.path.lexists(p) for p in aside):
                continue
            try:
                for kept, final in aside.items():
                    os.rename(at[final], kept)
                    at[final] = kept
            except OSError:
                break
            return _paths_said(at.values())
    return _copy_aside(at)


def _copy_aside(at: dict[Path, Path]) -> str:
    """The last resort of :func:`_keep_aside`, the folder refusing every name beside --out (a link, a copy and a
    rename: a folder gone read-only): each file still under its temporary name (``at``: final name -> where its
    data is) is copied into the system's temporary folder and its temporary file removed, so that the next record,
    which removes temporary files as an interrupted one's leftovers, removes none of this one's data.  Where the
    files are, as a message says it; a temporary file that stays is named as one (the folder refusing its removal:
    a copy is elsewhere; no copy possible: the data is only there)."""
    import shutil

    from bench.atomic import TEMP_SUFFIX, save_in_temp_folder

    notes = []
    for final, where in list(at.items()):
        if not where.name.endswith(TEMP_SUFFIX):
            continue  # (renamed to its kept name before the rename of another failed)
        try:
            at[final] = save_in_temp_folder(lambda path: shutil.copyfile(where, path), f"{final.stem}.kept-",
                                            final.suffix)
        except OSError as e:
            notes.append(f"{escaped(str(where))} is a temporary name, which the next record into that folder "
                         f"removes as an interrupted one's, and no copy could be made ({e.strerror or e})")
            continue
        try:
            os.unlink(where)
        except OSError:
            notes.append(f"the temporary file {escaped(str(where))}, a copy, stays (the next record there removes it)")
    return _paths_said(at.values()) + "".join(f"; {n}" for n in notes)


def _paths_said(paths) -> str:
    """Files for a message: each path escaped (one line, :func:`~bench.errors.escaped`), joined by "and"."""
    return " and ".join(escaped(str(p)) for p in paths)


def _open_driver(port: str, baud: int):
    from bench.hosts.driver import BridgeDriver

    try:
        return BridgeDriver(port, baudrate=baud)
    except (OSError, ValueError) as e:
        code = getattr(e, "errno", None)
        msg = os.strerror(code) if isinstance(code, int) else str(e)
        if "exclusively lock" in str(e):
            msg = "another program has it open (another record or host?); one host at a time"
        raise OSError(f"argument port: cannot open {escaped(port)}: {msg}") from None


def _cmd_record(a) -> int:
    """The recording, holding --out's lock from start to end (:class:`~bench.reporting.outdir.OutFile`): two
    records never write one file, and the temporary files of a record killed as it wrote are removed and named."""
    from bench.reporting.outdir import OutFile, folder_named

    out = Path(a.out)
    where = folder_named(out, "--out", not typed(a, "out"), "file")
    _refuse_overwriting(out, a.csv, a.force, where)
    with say_leftovers(OutFile.open(out, "--out", "record", "this recording", beside=(_csv_beside(out).name,),
                                    where=where)):
        return _record(a, out, where)


def _record(a, out: Path, where: str) -> int:
    from tqdm import tqdm

    from bench.hosts.driver import CMD_START, SLOT_RATE_HZ

    frames, end, detail = [], "complete", ""
    recorded_s = 0.0
    drv = None
    with sigterm_raises():
        try:
            drv = _open_driver(a.port, a.baud)
            with contextlib.suppress(OSError, AttributeError):  # what an earlier host left unread (not a URL's)
                drv.serial.reset_input_buffer()
            started = drv.start()
            if drv.wait_for(CMD_START, timeout_s=5) is None:
                drv.close()
                if drv.disconnected:
                    raise OSError(f"{escaped(a.port)}: the port closed before the bridge answered START")
                raise OSError(f"{escaped(a.port)}: no answer to START within 5 s (is the bridge running?)")
            drv.count_afresh(after_reply_to=started)  # the recording's frames, CRC errors and drops: from its START on
            if not a.quiet:
                print(f"recording {a.seconds:g} s from {escaped(a.port)}", file=sys.stderr, flush=True)
            with tqdm(total=round(a.seconds, 3), unit="s", disable=a.quiet,
                      bar_format="{l_bar}{bar}| {n:.2f}/{total:.2f} s") as bar:
                for f in drv.frames(timeout_s=a.idle_timeout):
                    frames.append(f)
                    dt = len(f.channels) / SLOT_RATE_HZ
                    recorded_s += dt
                    # the stream's span: what arrived plus what was lost on the way (frames of the same length)
                    span = recorded_s + drv.parser.stats.dropped_frames * dt
                    bar.update(min(span, a.seconds) - bar.n)
                    if span >= a.seconds - 1e-9:
                        break
                else:
                    end = "disconnected" if drv.disconnected else "stream stopped"
                    detail = ("the bridge went away (its port closed)" if drv.disconnected else
                              f"no data for {a.idle_timeout:g} s")
        except Terminated:
            end, detail = "terminated", "terminated by SIGTERM"
        except KeyboardInterrupt:
            end, detail = "interrupted", "interrupted by Ctrl-C (SIGINT)"
        except OSError as e:
            if not frames:
                raise
            end, detail = "port error", f"port error: {e}"
    with signals_deferred():
        if drv is not None:
            try:
                if not drv.disconnected:
                    drv.stop()
                drv.close()
            except Exception:  # noqa: BLE001 - the port may be gone; what was received is saved regardless
                pass
        status = END_STATUS[end]
        if not frames:
            print(f"error: {detail or 'no frames arrived'}; nothing received, no file written", file=sys.stderr)
            return status if end in ("interrupted", "terminated") else 2  # no stream there: as a bad port
        st = drv.parser.stats
        meta = {"end": end, "requested_s": a.seconds, "recorded_s": recorded_s, "dropped_frames": st.dropped_frames,
                "crc_errors": st.crc_errors}
        written, not_written, lost = [], {}, None
        try:
            written, not_written = _save_recording(out, frames, meta, a.csv, force=a.force, where=where)
        except OutputNotWritten as e:  # its message says where the NPZ went instead (or that it is lost)
            lost = e
    if lost:
        print(f"error: {lost}", file=sys.stderr)
        status = max(status, 1)  # (a recording a signal ended keeps 130 / 143)
    summary = (f"wrote {', '.join(escaped(str(p)) for p in written) or 'nothing at --out'}: {len(frames)} frames "
               f"({recorded_s:.2f} "
               f"s of {a.seconds:g} s asked); CRC errors {st.crc_errors}, dropped frames {st.dropped_frames}, bytes "
               f"skipped {st.bytes_skipped}")
    print(summary)
    for path, why in not_written.items():
        print(f"error: {escaped(str(path))} not written ({why}); {escaped(str(out))} holds every sample",
              file=sys.stderr)
        status = max(status, 1)
    if end != "complete":
        print(f"warning: partial recording: {detail} after {recorded_s:.2f} s of the {a.seconds:g} s asked "
              f"(exit status {status})", file=sys.stderr)
    return status


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    from bench.cli.scenes import scene_argument

    br = sub.add_parser(
        "bridge", help="run the bridge firmware against emulated sensors on a serial port (pty)",
        description="Compiles and runs the reference bridge firmware (firmware_tests/firmware) against emulated "
                    "sensors in virtual time and exposes its UART as a pty that any program can open as a serial "
                    "port. Real-time paced unless --fast. With --scene sensor k is the scene's sensor k "
                    "(unit, parameters, its faults, noise, fidelity, seed; the stimuli addressed to it) and the scene's "
                    "host.sequence becomes the firmware's sampling pattern.\n\n"
                    "The host's receive buffer holds --rx-buffer bytes: paced, a host that stops reading loses "
                    "what does not fit (an overrun, as on a real UART without flow control) and the firmware "
                    "streams on; with --fast the firmware waits for a reading host instead. Stops on Ctrl-C or "
                    "SIGTERM.\n\n"
                    "  biotac-bench bridge --sensors 3                 # prints the pty's path; Ctrl-C to stop\n"
                    "  biotac-bench bridge --scene taps --fast         # the scene's sensors; waits for the host\n"
                    "  biotac-bench record /dev/pts/5 --seconds 5      # from another shell: the path it printed",
        formatter_class=fmt)
    br.add_argument("--sensors", type=whole(1, 5), default=None,
                    help="emulated sensors, 1 to 5 (default: the scene's count with --scene, else 1)")
    br.add_argument("--scene", type=scene_argument,
                    help="scene file or shipped scene name: sensors built from it (units, variants, each its own "
                         "stimuli; --sensors, if given, at least the scene's count)")
    br.add_argument("--seed", type=any_seed,
                    help="seed (default: the scene's, else 0); sensor k draws its noise from seed + k - 1, "
                         "with a scene or without (as every route numbers sensors)")
    br.add_argument("--seconds", type=number(0, lo_open=True), help="stop after this many wall-clock seconds")
    br.add_argument("--speed", type=number(0, lo_open=True), default=1.0,
                    help="virtual seconds per wall second when paced (> 0; default 1)")
    br.add_argument("--fast", action="store_true", help="run as fast as possible instead of real time")
    br.add_argument("--baud", type=whole(50, 12_000_000), default=3_000_000,
                    help="the UART's baud rate (paces the line; default 3000000)")
    br.add_argument("--rx-buffer", type=whole(1024, 1 << 24), default=4096, metavar="BYTES",
                    help="the host's receive buffer in bytes (default 4096)")
    br.add_argument("--firmware", nargs="+", type=firmware_file, metavar="FILE",
                    help="your firmware instead of the reference one: its C sources (built with bt_hal.h and "
                         "bt_bridge.h on the include path) or one built .so; it must export bt_bridge_size, "
                         "bt_init, bt_step and bt_set_pattern (firmware_tests/firmware/bt_bridge.h)")
    br.add_argument("--spi", choices=["software", "rtl"], default=None,
                    help="the sensors' SPI side: the software model, or the Verilog RTL in the C++ harness "
                         "(default: the scene's host.spi, else software)")
    br.set_defaults(func=_cmd_bridge)

    rc = sub.add_parser(
        "record", help="record a bridge's serial stream to NPZ (and CSV)",
        description="Reads the bridge firmware's frames from a serial port (a device, a pty, or a pyserial URL "
                    "such as socket://host:port) and writes codes, status and sequence numbers to NPZ; reports "
                    "CRC errors and dropped frames.\n\n"
                    "Whatever ends the recording, what was received is written (to a temporary name, then "
                    "renamed), with 'end', 'requested_s' and 'recorded_s' in the file. An earlier recording at "
                    "--out (or a CSV beside it) is refused before anything is recorded unless --force, which "
                    "replaces it and removes its CSV if this recording writes none (a CSV there that is not a "
                    "recording's is refused even with --force). Without --force, a file that appears there "
                    "during the recording is not replaced either: the recording is then kept beside it (--out r.npz: "
                    "r.kept-<8 hex digits>.npz, and .csv), which the error gives; rename it to use it. What a "
                    "record killed as it wrote left (.NAME.<random>.part) is removed, and named, by the next record "
                    "to the same --out; two records never write one --out at once (the second is refused). A full "
                    "disk loses nothing received: a CSV that does not fit is named and the NPZ placed; an NPZ that "
                    "cannot be written goes to the system's temporary folder, which the error names. The port is "
                    "opened exclusively (another record, or any program locking it, is refused; CRC errors and "
                    "drops count from this recording's START). Exit status: 0 complete; 1 the stream stopped, the "
                    "bridge went away or the port failed before --seconds (a warning says so), or a file could "
                    "not be written; 130 Ctrl-C; 143 SIGTERM; 2 bad arguments, nothing received, or --out taken "
                    "during the recording.\n\n"
                    "codes[frame, slot, k] is the k-th present sensor ('layout' = 'compact'); if the pattern or "
                    "the set of sensors changes during the recording, codes[frame, slot, sensor - 1] with status "
                    "255 where nothing was sampled ('layout' = 'by_sensor').\n\n"
                    "  biotac-bench record /dev/pts/5 --seconds 5 --out rec.npz --csv   # the pty `biotac-bench "
                    "bridge` printed\n"
                    "  biotac-bench record socket://bench-pc:7000 --seconds 60 --out long.npz --force",
        formatter_class=fmt)
    rc.add_argument("port", help="the bridge's serial port: a device, a pty (`biotac-bench bridge` prints it) or "
                                 "a pyserial URL such as socket://host:port")
    rc.add_argument("--seconds", type=number(0, 86_400 * 7, lo_open=True), default=1.0,
                    help="seconds of stream to record (> 0; default 1)")
    rc.add_argument("--out", type=recording_file, default="out/recording.npz", metavar="FILE", action=NotedWhenTyped,
                    help="the NPZ file to write (default out/recording.npz); a folder is refused: give the file's "
                         "name in it")
    rc.add_argument("--csv", action="store_true",
                    help="also write the frames as CSV beside the NPZ (same name, suffix .csv): seq, slot, "
                         "channel (its name, e.g. PAC or E7, as in run's samples.csv; the NPZ's 'channels' holds "
                         "the channel indices), sensor, code, status")
    rc.add_argument("--force", action="store_true",
                    help="replace an earlier recording at --out (and remove its CSV beside it when this recording "
                         "writes none); a .csv beside --out that is not a recording's is refused, never removed")
    rc.add_argument("--baud", type=whole(50, 12_000_000), default=3_000_000,
                    help="the serial line's baud rate (default 3000000, the bridge's)")
    rc.add_argument("--idle-timeout", type=number(0, 3600, lo_open=True), default=5.0, metavar="S",
                    help="the stream has stopped when nothing arrives for this long (default 5 s)")
    rc.add_argument("--quiet", action="store_true", help="no progress bar and no 'recording ...' line")
    rc.set_defaults(func=_cmd_record)

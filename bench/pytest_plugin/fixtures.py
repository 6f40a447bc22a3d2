"""pytest plugin: fixtures that hand your own tests an emulated BioTac.

Installed with the package (entry point ``pytest11``), so in any test:

    def test_my_driver_reads_rest_noise(biotac_serial_port):
        my_driver = MyDriver(biotac_serial_port)        # a real serial device path (a pty)
        my_driver.start()     # your driver sends START first: like the real bridge, the firmware streams nothing
        ...                   # until the host sends START (0xAA 0x55 0x01 0x00 0x00 0xAC 0xFB: type 1, CRC-16)

    def test_with_the_bench_driver(biotac_serial_port):
        from bench.hosts.driver import BridgeDriver
        driver = BridgeDriver(biotac_serial_port)
        driver.start()                                  # sends START
        frame = next(driver.frames(max_frames=1))       # codes[slot, sensor]: the 44-slot default frame
        assert frame.codes.shape == (44, 1)
        driver.close()

    def test_my_host_code(biotac_bridge):
        bench = biotac_bridge(n_sensors=3, stimuli=[Tap(0.5, 1.0)])   # firmware on a pty, 3 sensors
        driver = BridgeDriver(bench.port); driver.start()               # streaming starts at START
        bench.at(bench.virtual_time + 1.0, lambda board: board.unplug(2))   # a fault, in virtual time
        ...

    def test_my_spi_code(biotac_sensor):
        spi = biotac_sensor(stimuli=[Tap(0.1, 1.0)])   # the sensor's SPI side, in process
        miso = spi.exchange(TransferBatch(start_s, mosi_words))   # or spi.bus for multi-sensor traffic

Fixtures
    biotac_sensor       factory -> emulator.spi.model.SensorPort over an emulated sensor (in process)
    biotac_bridge       factory -> bench.hosts.bridge.FirmwareBench: reference firmware on a pty (stopped at teardown),
                        at ``bench.port``.  The firmware speaks the real bridge's protocol: it answers each
                        command, and streams frames only after the host sends START
                        (``BridgeDriver(bench.port).start()``).
                        Unpaced by default: the firmware waits for your program to read, nothing is lost.  With
                        ``realtime=True`` the pty is a UART without flow control: a program that stops reading
                        overruns the 4096-byte receive buffer and loses frames (``keep_arrivals=True`` and
                        ``bench.overrun_frames()`` tell which), as a real one would
    biotac_serial_port  the pty path of a one-sensor bridge whose firmware is running and waiting for the host:
                        it sends nothing until START (``BridgeDriver(port).start()``, or the 7 bytes above)
    biotac_cheetah      factory -> bench.hosts.cheetah_server.CheetahBench: emulated sensors behind cheetah.so; run
                        your Cheetah-based program with ``cwd``/copy at ``.lib_dir`` and ``env=bench.env``.  One
                        program at a time may open the adapter; teardown is clean whatever the program did
                        (malformed requests are listed in ``bench.client_errors``); ``trace=True`` keeps every
                        transfer with its time

Sensor units: every factory takes a unit (``emulator.units``: a unit seed, "nominal" or a serial "BT..."):
``biotac_sensor(unit=17)``, ``biotac_bridge(3, units=[17, 18, "nominal"])`` (sensor k is ``units[k - 1]``; the
sensors read the default frame, sensor 1 feels ``stimuli``, sensor k draws its noise from ``seed + k``).  Each
sensor then carries the unit's parameters and its serial number (``sensor.serial``, None for the nominal unit;
``biotac_sensor`` also answers it as its serial property).
"""

from __future__ import annotations

import pytest


@pytest.fixture
def biotac_sensor():
    """Factory: ``biotac_sensor(stimuli=(), channels=..., seed=0, unit=None)`` -> the SPI side of an emulated
    sensor, in process (``spi.exchange(TransferBatch(...))``)."""
    from emulator.channels import DEFAULT_FRAME_NAMES
    from emulator.sensor import Sensor
    from emulator.spi.model import SensorPort

    def make(stimuli=(), channels=DEFAULT_FRAME_NAMES, seed: int = 0, unit=None, **sensor_kw):
        if unit is None:
            return SensorPort(Sensor(stimuli=list(stimuli), channels_read=channels, seed=seed, **sensor_kw))
        from emulator.spi.model import default_properties
        from emulator.units import unit as make_unit

        u = make_unit(unit)
        sensor = Sensor(params=u.params, stimuli=list(stimuli), channels_read=channels, seed=seed, **sensor_kw)
        sensor.serial = None if u.seed is None else u.serial
        return SensorPort(sensor, properties=default_properties(1, sensor.variant.name, serial=sensor.serial))

    return make


def unit_sensors(n_sensors: int, units, stimuli=(), seed: int = 1) -> dict:
    """Sensors 1..n of the given units (a list of n unit seeds / "nominal" / serials), reading the default frame;
    sensor 1 feels ``stimuli``; sensor k draws its noise from ``seed + k`` (as the benches' own sensors)."""
    from emulator.channels import DEFAULT_FRAME_NAMES
    from emulator.sensor import Sensor
    from emulator.units import unit

    units = list(units)
    if len(units) != n_sensors:
        raise ValueError(f"units = {units!r}: give one unit per sensor ({n_sensors})")
    out = {}
    for k, which in enumerate(units, start=1):
        u = unit(which)
        out[k] = Sensor(params=u.params, stimuli=list(stimuli) if k == 1 else [], channels_read=DEFAULT_FRAME_NAMES,
                        seed=seed + k)
        out[k].serial = None if u.seed is None else u.serial  # nominal: the port's own default serial
    return out


def _benches(bench_class):
    """A factory fixture's body: start ``bench_class(n_sensors, stimuli=..., **kw)`` on demand, stop each after."""
    started = []

    def make(n_sensors: int = 1, stimuli=(), units=None, **kw):
        if units is not None:
            kw["sensors"] = unit_sensors(n_sensors, units, stimuli, kw.pop("seed", 1))
        bench = bench_class(n_sensors, stimuli=stimuli, **kw).start()
        started.append(bench)
        return bench

    yield make
    for bench in started:
        bench.stop()


@pytest.fixture
def biotac_bridge():
    """Factory: ``biotac_bridge(n_sensors=1, stimuli=(), units=None, **kw)`` -> the bridge firmware on a pty at
    ``bench.port``; it streams frames only after the host sends START (``BridgeDriver(bench.port).start()``)."""
    from bench.hosts.bridge import FirmwareBench

    yield from _benches(FirmwareBench)


@pytest.fixture
def biotac_serial_port(biotac_bridge):
    """The pty path of a one-sensor bridge, firmware running and waiting for the host: it sends nothing until
    START (``BridgeDriver(port).start()``, or the bytes AA 55 01 00 00 AC FB)."""
    return biotac_bridge(1).port


@pytest.fixture
def biotac_cheetah():
    """Factory: ``biotac_cheetah(n_sensors=1, stimuli=(), units=None, **kw)`` -> emulated sensors behind cheetah.so
    (``bench.lib_dir``, ``bench.env`` for your Cheetah-based program)."""
    from bench.hosts.cheetah_server import CheetahBench

    yield from _benches(CheetahBench)

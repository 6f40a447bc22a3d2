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

    def test_when_each_sample_was_taken(biotac_bridge):
        bench = biotac_bridge()
        driver = BridgeDriver(bench.port, sample_times=bench.sample_times); driver.start()
        frame = next(driver.frames(max_frames=1))
        frame.t_s           # each slot's sample time: virtual s from power-on, 1/4400 s apart

    def test_a_scene_on_the_bridge(biotac_bridge):
        bench = biotac_bridge(scene="taps")      # a shipped scene's name, a scene file, or a Scene
        ...

    def test_my_spi_code(biotac_sensor):
        spi = biotac_sensor(stimuli=[Tap(0.1, 1.0)])   # the sensor's SPI side, in process
        miso = spi.exchange(TransferBatch(start_s, mosi_words))   # or spi.bus for multi-sensor traffic

Fixtures
    biotac_sensor       factory -> emulator.spi.model.SensorPort over an emulated sensor (in process)
    biotac_bridge       factory -> bench.hosts.bridge.FirmwareBench: reference firmware on a pty (stopped at teardown),
                        at ``bench.port``.  The firmware speaks the real bridge's protocol: it answers each
                        command, and streams frames only after the host sends START
                        (``BridgeDriver(bench.port).start()``).  ``bench.sample_times(frame)``: the virtual
                        time (s from power-on) of each slot's sample of a frame read from it —
                        ``BridgeDriver(bench.port, sample_times=bench.sample_times)`` puts it in every
                        DataFrame's ``t_s`` column (the wire carries no time: without it ``t_s`` is None).
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

Keywords (every one optional)
    ``biotac_sensor(...)``: one sensor, whose SPI side your code drives
        spi           "software" (default; with ``scene``: its host.spi; the session's ``--biotac-spi`` replaces
                      that default) or "rtl": the Verilog twin in the C++ Verilator harness, behind the same
                      ``exchange`` (its process is stopped after the test)
        stimuli       what the sensor feels (``emulator.stimuli``; default: nothing)
        channels      the channels it answers (default: its variant's whole frame — E1..E24 on a "biotac-sp";
                      others answer 0xA558, channel not recognised)
        seed          its noise seed (default: the session's, else 0; with ``scene``: the session's, else the
                      scene's) — it is sensor 1 of the seed convention below
        unit          its unit (``emulator.units``): a unit seed, "nominal" (default) or a serial "BT..."
        variant       "biotac" (default, 19 electrodes) or "biotac-sp" (24)
        params        ``SensorParams`` (with ``unit``: the unit's spreads are drawn around them)
        fidelity, noise, faults   as ``emulator.sensor.Sensor``: profile name, ``NoiseSources``, sensor faults
                      ({"electrode_open": [3]}, ...); SPI faults: ``spi.faults = Faults(...)``
        block_s, start_s, record_signals   as ``emulator.sensor.Sensor``
        scene         a scene (below): the sensor is the scene's sensor 1; only ``seed`` may be given with it
    ``biotac_bridge(...)`` / ``biotac_cheetah(...)``: sensors 1..n on a bus
        n_sensors     1..5 (default: ``len(units)``, the number of variants given, the scene's count, else 1)
        stimuli       what sensor 1 feels (sensor k > 1 feels nothing)
        units         one unit per sensor (sensor k is ``units[k - 1]``; default: all nominal)
        variant       "biotac" or "biotac-sp" for every sensor, or one per sensor; each sensor then reads its
                      variant's whole frame (an all-SP bridge streams the 54-slot frame)
        seed          sensor k draws its noise from ``seed + k - 1`` (default: the session's, else 0; with
                      ``scene``: the session's, else the scene's)
        params, fidelity, noise, faults   for every sensor, as for ``biotac_sensor``
        sensors       your own ``{k: Sensor}`` instead (refused with units, variant, stimuli, params, fidelity,
                      noise, faults or scene: they would be ignored; an n_sensors beside them must be their count)
        scene         the sensors of a scene (below); refused with sensors, stimuli, units, variant, params,
                      noise, faults (the scene says them) and, on the bridge, pattern (its host.sequence is the
                      pattern); a ``fidelity`` (and ``seed``) beside it replaces the scene's own
      biotac_bridge only (``FirmwareBench``):
        realtime      pace the firmware to the wall clock (default False: it waits for your program to read)
        speed         virtual seconds per wall second when paced (default 1)
        spi           "software" (default; with ``scene``: its host.spi; ``pytest --biotac-spi rtl|software``
                      replaces that default for the whole session) or "rtl" (the Verilog twin)
        pattern       the firmware's sampling pattern: channel indices (default: the variant's default frame)
        baudrate      the UART's (default 3000000); rx_buffer: the host's receive buffer (bytes, default 4096)
        keep_arrivals keep every byte's arrival (``bench.overrun_frames()``)
        host_gone_s   unpaced, how long (wall s, default 0.2) your program may leave the receive buffer full
                      before it is taken as gone and bytes overrun: raise it for a test that pauses on purpose,
                      or on a loaded CI machine
        pull_up       MISO pulled up when no sensor drives it (default False)
        corrupt_rate, drop_rate   line faults: the probability that each byte is corrupted / dropped
        step_s        the firmware's virtual-time step (s, default 0.01)
        firmware      your firmware instead of the reference one: a list of C source files (built with
                      ``bench.hosts.cosim.build_firmware``) or a built library; a bt_step that never returns
                      fails the test at teardown, naming the hang
        SPI faults in virtual time: ``bench.at(t_s, lambda board: setattr(board.bus.ports[k], "faults",
        Faults(miso_stuck=1)))`` (either SPI bus: over ``spi="rtl"`` from the same transfer, the same words);
        glitches, brown-outs and hot-plugging: ``board.glitch(k)``, ``board.reset_at(k, t_s)``,
        ``board.unplug(k)``, ``board.plug(k)`` (either SPI bus, the same frames).  An action that raises stops the
        bench: the error names the action (where it is written), the instant it was due and what it raised, in the
        failing test's report and at teardown
      biotac_cheetah only (``CheetahBench``):
        trace         keep every transfer (start s, select code, bits, MOSI) in ``bench.trace``
        spi           "software" (default; with ``scene``: its host.spi; the session's ``--biotac-spi`` replaces
                      that default) or "rtl": the adapter clocks the Verilog twin (SPI mode 3 refused there, as a
                      client error: see ``CheetahBench``)
        request_wait_s  how long (wall s) the test's end waits for a request still being clocked before
                      ending it (default 5; over the RTL its harness is ended under it and the test fails)

Seeds, one convention: sensor k of a call (or session) whose seed is S draws its noise from ``S + k - 1``
(:func:`bench.scenes.scene.sensor_seed`) whichever factory or route makes it — ``biotac_sensor(seed=S)`` is
sensor 1, and a scene's sensor k draws ``S + k - 1`` too — so the same S gives sensor k the same noise on the bridge,
behind the Cheetah adapter and in process.

Session settings: ``pytest --biotac-fidelity NAME --biotac-seed N`` (or ``biotac_fidelity = NAME`` /
``biotac_seed = N`` in the ini file; the command line wins) set the fidelity profile and the seed of every call of
the three factories (a scene's own replaced); a test's ``@pytest.mark.biotac(fidelity=..., seed=...)`` replaces
them for that test, and a call's ``fidelity=``/``seed=`` replaces all of them.  Your own ``sensors=`` keep their
own.  A value that is not one stops the session at its start (or fails the marked test) in one line naming the
option, the value and the allowed ones (:mod:`bench.pytest_plugin.hooks`).

The factories are called (``spi = biotac_sensor()``); using one as the sensor or bench it makes is an
AttributeError saying so.  A bench that fails when it is stopped (a hung firmware, an error in its thread; a Cheetah
program's request still being clocked over the RTL, whose harness process is then ended under it) fails the test at
teardown with that error in one message, after every bench of the test has been stopped.

``scene``: a ``Scene``, a scene file's path, or a shipped scene's name as ``biotac-bench run`` takes it ("taps").
Sensor k is the scene's sensor k (unit, parameters, variant, stimuli, faults, noise, fidelity; see
``bench.hosts.scene_sensors``); on the bridge its ``host.sequence`` becomes the firmware's pattern and
``host.spi`` the SPI side.  Behind the Cheetah adapter your program is the host: of the scene's [host] section
only ``spi`` is used (the SPI side the adapter clocks).  A scene that is not valid,
or a keyword the fixture does not take, fails the test with the problem in one message (no traceback).

A failing test's report says what every sensor and bench its factories made was and felt (the call, each
sensor's serial, seed, fidelity, sensor and SPI faults and stimuli, the bench's virtual time: "Captured biotac
call"), and ``--junitxml`` keeps the same text as each test's property ``biotac`` (:mod:`bench.pytest_plugin.hooks`).

Sensor units: each sensor carries its unit's parameters and serial number (``sensor.serial``, None for the nominal
unit), and answers that serial as its serial property (a BioTac SP's as "BTSP…"; the nominal unit: its port's
default, one per sensor number).
"""

from __future__ import annotations

import inspect

import pytest

#: The plugin's hooks (what a failing test's sensors were and felt: its report and JUnit property ``biotac``).
pytest_plugins = ("bench.pytest_plugin.hooks",)

#: Keywords of emulator.sensor.Sensor the factories pass on to every sensor they build.
SENSOR_KEYWORDS = ("params", "fidelity", "noise", "faults", "block_s", "start_s", "record_signals")
#: What a scene (or your own ``sensors=``) already says about the sensors: refused beside it.
SENSOR_DESCRIPTION = ("stimuli", "units", "variant") + SENSOR_KEYWORDS
#: The seed of a call that gives none, in a session without ``--biotac-seed``: sensor k draws ``DEFAULT_SEED + k - 1``
#: (:func:`bench.scenes.scene.sensor_seed`), as a scene's sensors do from its default seed.
DEFAULT_SEED = 0


def _fail(message: str):
    """Fail the calling test with ``message`` alone (a misused fixture: no traceback into the plugin)."""
    __tracebackhide__ = True
    raise pytest.fail.Exception(message, pytrace=False) from None  # not "during handling of ... another exception"


def with_settings(scene, settings: dict):
    """``scene`` with the session's or the test's marker's sensor settings (``settings``: fidelity and seed, those
    set) in place of its own, as ``biotac-bench run --fidelity/--seed`` replace them
    (:func:`bench.scenes.scene.with_overrides`: validated again, its slides drawn from the new seed)."""
    from bench.scenes.scene import with_overrides

    return with_overrides(scene, {f"scene.{name}": value for name, value in settings.items()})


def over_scene(settings: dict, kw: dict) -> dict:
    """The settings a call's scene is read with: the session's or the test's marker's (``settings``), the call's own
    ``fidelity=`` over them (taken out of the call's keywords ``kw``), as ``run SCENE --fidelity`` replaces a scene's."""
    return {**settings, **({"fidelity": kw.pop("fidelity")} if "fidelity" in kw else {})}


def load_scene_like(scene):
    """A :class:`~bench.scenes.scene.Scene` from a Scene, a scene file's path or a shipped scene's name (as
    ``biotac-bench run`` takes it); :class:`~bench.errors.SceneError` for what is wrong."""
    from bench.cli.scenes import scene_file
    from bench.scenes.scene import Scene, load_scene

    return scene if isinstance(scene, Scene) else load_scene(scene_file(str(scene)))


def one_sensor(unit=None, variant=None, stimuli=(), channels=None, seed: int = DEFAULT_SEED, params=None,
               **sensor_kw):
    """An emulated sensor of ``unit`` (None/"nominal", a unit seed or a serial; its spreads drawn around ``params``)
    and ``variant`` (None: "biotac"), answering ``channels`` (None: its variant's whole frame), carrying the unit's
    serial as ``.serial`` (None for the nominal unit: its port answers the default serial)."""
    from emulator.channels import variant as variant_of
    from emulator.sensor import Sensor
    from emulator.units import unit as unit_of

    from emulator.spi.model import variant_serial

    u = unit_of(unit, base=params)
    v = variant_of("biotac" if variant is None else variant)
    variant_serial(u.serial, v.name)  # ValueError: a "BTSP..." serial on a sensor that is not an SP
    sensor = Sensor(params=u.params, stimuli=list(stimuli), seed=seed, variant=v.name,
                    channels_read=v.frame_names if channels is None else channels, **sensor_kw)
    sensor.serial = None if u.seed is None else u.serial
    return sensor


def unit_sensors(n_sensors: int, units=None, stimuli=(), seed: int = DEFAULT_SEED, variant=None,
                 **sensor_kw) -> dict:
    """Sensors 1..n (:func:`one_sensor`) of ``units`` (None: all nominal; else one per sensor) and ``variant`` (one
    for all, or one per sensor), each reading its variant's whole frame; sensor 1 feels ``stimuli``; sensor k draws
    its noise from :func:`bench.scenes.scene.sensor_seed` (``seed + k - 1``, as a scene's sensor k); ``sensor_kw``
    go to every sensor."""
    from bench.scenes.scene import sensor_seed

    units = ["nominal"] * n_sensors if units is None else list(units)
    variants = [variant] * n_sensors if variant is None or isinstance(variant, str) else list(variant)
    if len(units) != n_sensors:
        raise ValueError(f"units = {units!r}: give one unit per sensor ({n_sensors})")
    if len(variants) != n_sensors:
        raise ValueError(f"variant = {variant!r}: give one variant for every sensor, or one per sensor ({n_sensors})")
    return {k: one_sensor(which, variants[k - 1], stimuli if k == 1 else (), seed=sensor_seed(seed, k), **sensor_kw)
            for k, which in enumerate(units, start=1)}


def _given(**kw) -> dict:
    """The keywords given a value (not None)."""
    return {k: v for k, v in kw.items() if v is not None}


def _check_keywords(fixture: str, given: dict, allowed) -> None:
    """Fail the test if ``given`` holds a keyword not in ``allowed`` (naming it and the fixture's keywords)."""
    __tracebackhide__ = True
    unknown = sorted(set(given) - set(allowed))
    if unknown:
        _fail(f"{fixture}(): unknown keyword(s) {', '.join(unknown)}; it takes {', '.join(sorted(allowed))}")


def _check_values(fixture: str, n_sensors=None, stimuli=None, seed=None) -> None:
    """Fail the test if ``n_sensors`` is not a whole number 1..MAX_SENSORS, ``stimuli`` not a list of stimuli or
    ``seed`` not a seed (:func:`bench.scenes.limits.seed_problem`: 0 to MAX_SEED, as a scene's)."""
    __tracebackhide__ = True
    import operator

    from bench.scenes.limits import MAX_SENSORS, seed_problem

    if n_sensors is not None:
        try:
            whole = None if isinstance(n_sensors, bool) else operator.index(n_sensors)  # numpy integers too
        except TypeError:
            whole = None
        if whole is None or not 1 <= whole <= MAX_SENSORS:
            _fail(f"{fixture}(): n_sensors = {n_sensors!r}: a whole number from 1 to {MAX_SENSORS}")
    if seed is not None and (problem := seed_problem(seed)):
        _fail(f"{fixture}(): seed = {problem}")
    if stimuli is not None and not isinstance(stimuli, (list, tuple)):
        _fail(f"{fixture}(): stimuli = {stimuli!r}: give a list of stimuli (emulator.stimuli), e.g. "
              f"stimuli=[Tap(0.5, 1.0)]")


def _refuse_beside(fixture: str, what: str, given: dict, refused) -> None:
    """Fail the test if any of ``refused`` was given beside ``what`` (scene or sensors), which already says it."""
    __tracebackhide__ = True
    clash = [k for k in refused if k in given]
    if clash:
        _fail(f"{fixture}(): {', '.join(clash)} given with {what}, which already describes the sensors; "
              f"leave {'it' if len(clash) == 1 else 'them'} out (or {what})")


class Factory:
    """A factory fixture's value: call it to get a sensor or a bench; using it as one (``biotac_sensor.exchange``)
    is an AttributeError saying to call it first (it had been "'function' object has no attribute 'exchange'").
    What each call makes is remembered on the test's item ``node`` (:func:`bench.pytest_plugin.hooks.remember`), for
    the failure report and the JUnit property that say what the sensors were and felt."""

    def __init__(self, name: str, make, gives: str, node):
        self._name, self._make, self._gives, self._node = name, make, gives, node

    def __call__(self, *args, **kw):
        __tracebackhide__ = True
        from bench.paths import source_tree_problem
        from bench.pytest_plugin.hooks import remember  # (registered by pytest_plugins above)

        problem = source_tree_problem()  # a copy installed without its source tree's files
        if problem:
            _fail(f"{self._name}(): {problem}")
        made = self._make(*args, **kw)
        remember(self._node, self._name, args, kw, made)
        return made

    def __getattr__(self, attr: str):
        __tracebackhide__ = True
        if attr.startswith("__"):  # copy, pickle and friends look for these: no hint, the plain error
            raise AttributeError(attr)
        raise AttributeError(f"{self._name} is a factory fixture, not {self._gives}: call it first, e.g. "
                             f"x = {self._name}() (keywords in bench/pytest_plugin/fixtures.py), then x.{attr}")

    def __repr__(self):
        return f"<{self._name} factory: call it to get {self._gives}>"


@pytest.fixture
def biotac_sensor(request):
    """Factory: ``biotac_sensor(stimuli=(), channels=None, seed=0, unit=None, variant=None, scene=None, spi=None,
    **kw)`` -> the SPI side of an emulated sensor, in process (``spi.exchange(TransferBatch(...))``): the software
    model, or the Verilog RTL in the C++ harness (``spi="rtl"``, or the session's ``--biotac-spi``; stopped after the
    test); keywords in the module docstring."""
    from bench.errors import SceneError
    from bench.pytest_plugin.hooks import SPI_SIDES
    from bench.scenes.limits import SPI_SIDES_SAID
    from emulator.spi.model import SensorPort

    allowed = {"stimuli", "channels", "seed", "unit", "variant", "scene", "spi", *SENSOR_KEYWORDS}
    session_spi = request.config.getoption("biotac_spi", None)
    from bench.pytest_plugin.hooks import sensor_settings  # (registered by pytest_plugins above)

    settings = sensor_settings(request.node)  # the session's fidelity and seed, the test's marker's over them
    harnesses = []  # the RTL's harness processes this test started: stopped after it

    def side(sensor, spi: str):
        """The sensor's SPI side on ``spi``."""
        if spi == "software":
            return SensorPort(sensor)
        from emulator.rtl.harness import HarnessPeripheral

        harnesses.append(HarnessPeripheral(sensor))
        return harnesses[-1]

    def make(stimuli=None, channels=None, seed=None, unit=None, **kw):  # the first four by position too
        __tracebackhide__ = True
        _check_keywords("biotac_sensor", kw, allowed)
        _check_values("biotac_sensor", stimuli=stimuli, seed=seed)
        spi = kw.pop("spi", None)  # None: not given (the session's --biotac-spi, else the scene's or software)
        spi = session_spi if spi is None else spi
        if spi is not None and spi not in SPI_SIDES:
            _fail(f"biotac_sensor(): spi = {spi!r}: {SPI_SIDES_SAID}")
        kw.update(_given(stimuli=stimuli, channels=channels, seed=None if seed is None else int(seed), unit=unit))
        scene = kw.pop("scene", None)
        try:
            if scene is None:
                return side(one_sensor(**{"seed": DEFAULT_SEED, **settings, **kw}), spi or "software")
            scene_settings = over_scene(settings, kw)
            _refuse_beside("biotac_sensor", "scene", kw, ("stimuli", "channels", "unit", "variant", *SENSOR_KEYWORDS))
            from bench.hosts.scene_sensors import sensors_from_scene

            scene = with_settings(load_scene_like(scene), scene_settings)
            return side(sensors_from_scene(scene, scene.n_sensors, seed=kw.get("seed"))[1], spi or scene.spi)
        except (SceneError, ValueError, TypeError) as e:  # TypeError: "not a stimulus: 'tap'"
            _fail(f"biotac_sensor(): {e}")

    yield Factory("biotac_sensor", make, "a sensor's SPI side", request.node)
    for harness in harnesses:
        harness.close()


def _benches(fixture: str, bench_class, scene_kw, gives: str, node, defaults=None):
    """A factory fixture's body: build the sensors (module docstring; ``scene_kw(scene, n_sensors, seed, kw)``:
    the bench's keywords for a scene's sensors), start ``bench_class`` on them on demand, stop each after the
    test (``node``: the test's item, where what is made is remembered; ``defaults``: keywords a call that leaves
    them out gets, e.g. the session's ``--biotac-spi``)."""
    from bench.errors import BenchError

    own = set(inspect.signature(bench_class).parameters) - {"n_sensors", "stimuli", "seed", "sensors", "variant"}
    allowed = {"n_sensors", "stimuli", "seed", "sensors", "scene", *SENSOR_DESCRIPTION, *own}
    from bench.pytest_plugin.hooks import sensor_settings  # (registered by pytest_plugins above)

    settings = sensor_settings(node)  # the session's fidelity and seed, the test's marker's over them
    started = []
    ended = []

    def make(n_sensors: int | None = None, stimuli=None, units=None, **kw):  # the first three by position too
        __tracebackhide__ = True
        if ended:  # a bench started now would outlive every teardown
            raise RuntimeError(f"{fixture}(): called after the test it was given to had ended; a factory fixture "
                               f"serves its own test only")
        _check_keywords(fixture, kw, allowed)
        _check_values(fixture, n_sensors, stimuli, kw.get("seed"))
        kw = {**(defaults or {}), **kw}
        kw.update(_given(stimuli=stimuli, units=units, seed=None if kw.get("seed") is None else int(kw["seed"])))
        try:
            bench = bench_class(**_bench_kw(fixture, n_sensors, kw, scene_kw, settings))
        except (BenchError, ValueError, TypeError) as e:  # TypeError: "not a stimulus: 'tap'"; BuildError: firmware
            _fail(f"{fixture}(): {e}")
        started.append(bench.start())
        return bench

    yield Factory(fixture, make, gives, node)
    ended.append(True)
    problems = []
    for bench in started:  # every bench is stopped, whatever an earlier one reported
        where = getattr(bench, "port", None) or getattr(bench, "socket_path", "?")
        try:
            bench.stop()
        except (BenchError, RuntimeError) as e:  # a hung firmware, an error inside the bench's thread
            problems.append(f"{fixture}: bench on {where}: {e}")
        if getattr(bench, "stop_problem", None):  # (a CheetahBench: a request still clocked, its RTL harness ended)
            problems.append(f"{fixture}: bench on {where}: {bench.stop_problem}")
    if problems:
        _fail("\n".join(problems))


def _bench_kw(fixture: str, n_sensors: int | None, kw: dict, scene_kw, settings: dict) -> dict:
    """A bench's keywords for a factory's call (``kw``: its keywords but ``n_sensors``): the sensors built from a
    scene, taken as given, or built from units, variants and sensor keywords; the bench's own keywords passed on.
    ``settings``: the session's or the test's marker's fidelity and seed, for what the call leaves out (a scene's
    own replaced; your own ``sensors`` keep theirs)."""
    __tracebackhide__ = True
    kw = dict(kw)
    if "scene" in kw:
        scene_settings = over_scene(settings, kw)
        _refuse_beside(fixture, "scene", kw, ("sensors", "pattern") + SENSOR_DESCRIPTION)
        scene = with_settings(load_scene_like(kw.pop("scene")), scene_settings)
        return scene_kw(scene, n_sensors, kw.pop("seed", None), kw)
    seed = kw.pop("seed", settings.get("seed", DEFAULT_SEED))
    if "sensors" in kw:
        _refuse_beside(fixture, "sensors", kw, SENSOR_DESCRIPTION)
        sensors = kw.pop("sensors")
        if n_sensors is not None and n_sensors != len(sensors):
            _fail(f"{fixture}(): n_sensors = {n_sensors!r} given with {len(sensors)} sensors (numbered "
                  f"{sorted(sensors)}); leave n_sensors out or make them agree")
        return {**kw, "n_sensors": len(sensors) if n_sensors is None else n_sensors, "sensors": sensors,
                "seed": seed}
    units, variant, stimuli = kw.pop("units", None), kw.pop("variant", None), kw.pop("stimuli", ())
    if n_sensors is None:
        n_sensors = (len(units) if units is not None else
                     1 if variant is None or isinstance(variant, str) else len(variant))
    sensor_kw = {**({"fidelity": settings["fidelity"]} if "fidelity" in settings else {}),
                 **{k: kw.pop(k) for k in SENSOR_KEYWORDS if k in kw}}
    return {**kw, "n_sensors": n_sensors, "seed": seed,
            "sensors": unit_sensors(n_sensors, units, stimuli, seed, variant, **sensor_kw)}


def _bridge_scene_kw(scene, n_sensors: int | None, seed: int | None, kw: dict) -> dict:
    """FirmwareBench's keywords for ``scene``'s sensors (:func:`bench.cli.hosts.bridge_scene_kw`) and ``kw``."""
    from bench.cli.hosts import bridge_scene_kw

    spi = kw.pop("spi", None)
    return {**kw, **bridge_scene_kw(scene, n_sensors, seed, spi)}


def _cheetah_scene_kw(scene, n_sensors: int | None, seed: int | None, kw: dict) -> dict:
    """CheetahBench's keywords for ``scene``'s sensors and ``kw`` (the scene's [host] section is the user's
    program's business, but its ``spi``: the sensors' SPI side unless ``kw`` gives one)."""
    from bench.hosts.scene_sensors import sensors_from_scene

    n_sensors = scene.n_sensors if n_sensors is None else n_sensors
    return {**kw, "n_sensors": n_sensors, "sensors": sensors_from_scene(scene, n_sensors, seed=seed),
            "seed": scene.seed if seed is None else seed, "spi": kw.get("spi") or scene.spi}


@pytest.fixture
def biotac_bridge(request):
    """Factory: ``biotac_bridge(n_sensors=None, stimuli=(), units=None, variant=None, scene=None, **kw)`` -> the
    bridge firmware on a pty at ``bench.port``; it streams frames only after the host sends START
    (``BridgeDriver(bench.port).start()``); keywords in the module docstring."""
    from bench.hosts.bridge import FirmwareBench

    spi = request.config.getoption("biotac_spi", None)  # --biotac-spi: the session's SPI side
    yield from _benches("biotac_bridge", FirmwareBench, _bridge_scene_kw, "a FirmwareBench", request.node,
                        defaults={} if spi is None else {"spi": spi})


@pytest.fixture
def biotac_serial_port(biotac_bridge):
    """The pty path of a one-sensor bridge, firmware running and waiting for the host: it sends nothing until
    START (``BridgeDriver(port).start()``, or the bytes AA 55 01 00 00 AC FB)."""
    return biotac_bridge(1).port


@pytest.fixture
def biotac_cheetah(request):
    """Factory: ``biotac_cheetah(n_sensors=None, stimuli=(), units=None, variant=None, scene=None, **kw)`` ->
    emulated sensors behind cheetah.so (``bench.lib_dir``, ``bench.env`` for your Cheetah-based program); keywords
    in the module docstring."""
    from bench.hosts.cheetah_server import CheetahBench

    spi = request.config.getoption("biotac_spi", None)  # --biotac-spi: the session's SPI side
    yield from _benches("biotac_cheetah", CheetahBench, _cheetah_scene_kw, "a CheetahBench", request.node,
                        defaults={} if spi is None else {"spi": spi})

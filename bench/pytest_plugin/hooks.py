"""pytest plugin, hooks: what the emulated sensors of a test were and what they felt, shown where a CI looks.

Every sensor or bench a factory fixture (:mod:`bench.pytest_plugin.fixtures`) makes is remembered on the test's
item.  When the test fails (in its set-up, call or teardown) its report gains a section ``biotac`` — printed under
the failure as "Captured biotac call", and part of the ``<failure>`` text of ``--junitxml`` — saying, for each one, how it was made (the factory call as written), and
per sensor its variant, the serial it answers, its noise seed, fidelity profile, sensor faults, SPI faults set on
its port at that moment and every stimulus it feels, with the bench's virtual time reached: enough to rerun the
failure and to see what the sensor saw.  After the test's call the same text is recorded as the test's property
``biotac`` (``item.user_properties``), which ``--junitxml`` writes into the test case's ``<properties>``, passed
or failed (as pytest's ``record_property`` does: outside the strict xunit2 schema, which some CI servers check).

``--biotac-spi software|rtl`` runs every ``biotac_bridge``, ``biotac_cheetah`` and ``biotac_sensor`` of the session over that SPI side
unless its call gives ``spi=``: one test suite, run over the software model and again over the Verilog RTL in CI,
unchanged.  ``--biotac-fidelity NAME`` and ``--biotac-seed N`` (ini: ``biotac_fidelity``, ``biotac_seed``) set every
factory's sensors' fidelity profile and seed, under a test's ``@pytest.mark.biotac(fidelity=..., seed=...)`` and
its calls' keywords; values that are not ones stop the session at its start in one line.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bench.scenes.limits import SPI_SIDES, seed_problem  # SPI_SIDES: what ``--biotac-spi`` takes

#: The sensors and benches a test's factories made, in order: (fixture, the call as written, the object).
MADE = pytest.StashKey[list]()
#: The longest a keyword's value or a stimulus is written in the description (characters; longer ones are cut).
MAX_VALUE_CHARS = 300
#: At most this many stimuli are listed per sensor (the rest are counted).
MAX_STIMULI = 20


def _short(text: str) -> str:
    """``text`` cut to :data:`MAX_VALUE_CHARS` characters, saying so."""
    return text if len(text) <= MAX_VALUE_CHARS else text[:MAX_VALUE_CHARS - 1] + "…"


def remember(node, fixture: str, args: tuple, kw: dict, made) -> None:
    """Remember on the test item ``node`` that ``fixture(*args, **kw)`` made ``made`` (a SensorPort or a bench)."""
    call = ", ".join([_short(repr(a)) for a in args] + [f"{k}={_short(repr(v))}" for k, v in kw.items()])
    node.stash.setdefault(MADE, []).append((fixture, f"{fixture}({call})", made))


def _value_text(value) -> str:
    """A stimulus's field: numbers, strings and lists as their repr — a numpy number as the Python number it equals
    (``0.3``, not ``np.float64(0.3)``, nor a float32's kind alone); an object inside it (a slide's texture, its skin)
    by its kind and, if it has one, its name (``Texture('foam')``, ``Skin(…)``)."""
    if isinstance(value, (bool, int, float, str, list, tuple)):
        return repr(value.item() if isinstance(value, np.generic) else value)
    if isinstance(value, np.generic) and isinstance(value.item(), (bool, int, float)):
        return repr(value.item())
    name = getattr(value, "name", None)
    return f"{type(value).__name__}({name!r})" if isinstance(name, str) else f"{type(value).__name__}(…)"


def stimulus_text(stimulus) -> str:
    """A stimulus as its kind and the fields that are set (a dataclass's None fields left out), e.g.
    ``Tap(time_s=0.5, peak_N=1.0, ...)``; anything else as its repr."""
    if dataclasses.is_dataclass(stimulus) and not isinstance(stimulus, type):
        fields = ", ".join(f"{f.name}={_value_text(getattr(stimulus, f.name))}" for f in dataclasses.fields(stimulus)
                           if f.repr and getattr(stimulus, f.name) is not None)
        return _short(f"{type(stimulus).__name__}({fields})")
    return _short(repr(stimulus))


def sensor_lines(index: int, sensor, port) -> list[str]:
    """What sensor ``index`` is and feels (``port``: its SPI side on the bus, None while unplugged)."""
    from emulator.spi.model import Faults, default_serial, variant_serial

    variant = sensor.variant.name
    serial = default_serial(index, variant) if getattr(sensor, "serial", None) is None else \
        variant_serial(sensor.serial, variant)
    spi_faults = "unplugged" if port is None else (
        "none" if getattr(port, "faults", Faults()) == Faults() else
        ", ".join(f"{f.name}={getattr(port.faults, f.name)!r}" for f in dataclasses.fields(port.faults)
                  if getattr(port.faults, f.name) != getattr(Faults(), f.name)))
    stimuli = list(getattr(sensor, "stimuli", ()))
    lines = [f"  sensor {index}: {variant}, serial {serial}, seed {sensor.seed}, fidelity {sensor.fidelity.name}, "
             f"sensor faults {_short(repr(sensor.faults)) if sensor.faults else 'none'}, SPI faults {spi_faults}",
             f"    stimuli: {len(stimuli) or 'none'}"]
    lines += [f"      {stimulus_text(s)}" for s in stimuli[:MAX_STIMULI]]
    if len(stimuli) > MAX_STIMULI:
        lines.append(f"      … and {len(stimuli) - MAX_STIMULI} more")
    return lines


def describe(fixture: str, call: str, made) -> str:
    """How ``made`` was made (``call``) and, per sensor, what it is and feels; a bench's virtual time so far."""
    lines = [call]
    if fixture == "biotac_sensor":  # a SensorPort, or the RTL's HarnessPeripheral around its port
        port = getattr(made, "port", made)
        lines.append(f"  SPI side {'rtl' if port is not made else 'software'}")
        lines += sensor_lines(port.index, port.sensor, port)
        return "\n".join(lines)
    if fixture == "biotac_bridge":
        board = made.board
        lines.append(f"  port {made.port}, SPI side {board.spi}, virtual time {board.t:.6f} s"
                     + (f", line faults: {made.bytes_corrupted} byte(s) corrupted, {made.bytes_dropped} dropped"
                        if made.corrupt_rate or made.drop_rate else ""))
        if made.error is not None:  # its thread ended: the firmware, a HAL call or a test's action raised
            lines.append(f"  the bench stopped with an error: {made.error}")
        sensors, ports = board.sensors, board.bus.ports
    else:  # biotac_cheetah: the sensors behind the adapter
        lines.append(f"  socket {made.socket_path}, host time {made.t:.6f} s, {made.batches} batch(es) clocked"
                     + (f", client errors: {'; '.join(made.client_errors)}" if made.client_errors else ""))
        ports = made.bus.ports
        sensors = {k: p.sensor for k, p in ports.items()}
    for k in sorted(sensors):
        lines += sensor_lines(k, sensors[k], ports.get(k))
    return "\n".join(lines)


def description(item) -> str | None:
    """Every sensor and bench the test's factories made, described (None if it made none)."""
    made = item.stash.get(MADE, None)
    if not made:
        return None
    texts = []
    for fixture, call, obj in made:
        try:
            texts.append(describe(fixture, call, obj))
        except Exception as e:  # noqa: BLE001 - a description must never hide the test's own failure
            texts.append(f"{call}\n  (not described: {type(e).__name__}: {e})")
    return "\n".join(texts)


#: The session's sensor settings (``--biotac-fidelity``/``biotac_fidelity``, ``--biotac-seed``/``biotac_seed``),
#: checked at the session's start: {"fidelity": name, "seed": int}, with only those the session sets.
SESSION = pytest.StashKey[dict]()
#: The marker a test overrides the session's sensor settings with: ``@pytest.mark.biotac(fidelity=..., seed=...)``.
MARKER = "biotac"
#: What the marker and the session set: the command-line option and the ini name of each.
SETTINGS = {"fidelity": ("--biotac-fidelity", "biotac_fidelity"), "seed": ("--biotac-seed", "biotac_seed")}


def setting_problem(name: str, value) -> str | None:
    """What is wrong with ``value`` for the sensor setting ``name`` ("fidelity": a profile name of
    :data:`emulator.fidelity.PROFILES`; "seed": :func:`bench.scenes.limits.seed_problem`, 0 to
    :data:`~bench.scenes.limits.MAX_SEED` as a scene's seed), else None."""
    from emulator.fidelity import PROFILES

    if name == "fidelity":
        return None if isinstance(value, str) and value in PROFILES else \
            f"{value!r}: a fidelity profile, one of {', '.join(PROFILES)}"
    return seed_problem(value)  # (one bound and one message for every route: a scene's, the option, ini, marker, call)


def _setting(name: str, value):
    """``value`` of the checked sensor setting ``name`` as the sensors take it (a seed as an int)."""
    return int(value) if name == "seed" else value


def pytest_addoption(parser) -> None:
    """``--biotac-spi``: run every ``biotac_bridge``, ``biotac_cheetah`` and ``biotac_sensor`` of the session on that SPI side unless
    the test's call says ``spi=`` (a scene's ``host.spi`` is replaced, as ``biotac-bench run --spi`` replaces it).
    ``--biotac-fidelity``/``--biotac-seed`` (or the ini values ``biotac_fidelity``/``biotac_seed``; the command line
    wins): every factory's sensors' fidelity profile and seed unless the test's marker or call says otherwise."""
    group = parser.getgroup("biotac", "emulated BioTac (bench.pytest_plugin)")
    group.addoption(
        "--biotac-spi", choices=SPI_SIDES, default=None, dest="biotac_spi",
        help="SPI side of every biotac_bridge, biotac_cheetah and biotac_sensor whose call gives no spi=: the software model or "
             "the Verilog RTL (Verilator); default: the call's scene's host.spi, else software")
    group.addoption(
        "--biotac-fidelity", default=None, dest="biotac_fidelity", metavar="NAME",
        help="fidelity profile of every emulated sensor the biotac fixtures make (fast, default, reference) unless "
             "the test's @pytest.mark.biotac(fidelity=...) or call says otherwise; replaces a scene's; default: "
             "the ini value biotac_fidelity, else the call's scene's, else default")
    group.addoption(
        "--biotac-seed", default=None, dest="biotac_seed", metavar="N",
        help="seed of every biotac fixture call (sensor k draws seed + k - 1) unless the test's "
             "@pytest.mark.biotac(seed=...) or call says otherwise; replaces a scene's; default: the ini value "
             "biotac_seed, else the call's scene's, else 0")
    parser.addini("biotac_fidelity", "fidelity profile of the biotac fixtures' sensors (as --biotac-fidelity)",
                  type="string", default="")
    parser.addini("biotac_seed", "seed of the biotac fixtures' calls (as --biotac-seed)", type="string",
                  default="")


def pytest_configure(config) -> None:
    """Register the ``biotac`` marker; check the session's sensor settings (:data:`SESSION`) once, at its start:
    a value that is not one stops the session with one line naming the option (or ini name), the value and what
    it may be (a ``pytest.UsageError``, as pytest reports its own bad options)."""
    config.addinivalue_line("markers", f"{MARKER}(fidelity=None, seed=None): this test's emulated sensors' "
                                       "fidelity profile and seed, over --biotac-fidelity/--biotac-seed")
    session = {}
    for name, (option, ini) in SETTINGS.items():
        given = config.getoption(option.lstrip("-").replace("-", "_"), None)
        where = option
        if given is None:
            given, where = config.getini(ini).strip() or None, f"ini value {ini}"
        if given is None:
            continue
        problem = setting_problem(name, given)
        if problem:
            raise pytest.UsageError(f"{where} = {problem}")
        session[name] = _setting(name, given)
    config.stash[SESSION] = session


def sensor_settings(node) -> dict:
    """The sensor settings of the test ``node``: the session's (:data:`SESSION`) with its ``biotac`` marker's over
    them (the closest marker: a test's own over its class's or module's).  A marker with another keyword, a
    positional argument or a value that is not one fails the test with one line naming it."""
    __tracebackhide__ = True
    settings = dict(node.config.stash.get(SESSION, {}))
    marker = node.get_closest_marker(MARKER)
    if marker is None:
        return settings
    problems = [f"{k} = {v!r}: not a setting (it takes {', '.join(SETTINGS)})" for k, v in marker.kwargs.items()
                if k not in SETTINGS]
    problems += [f"{a!r}: give settings by keyword ({', '.join(SETTINGS)})" for a in marker.args]
    problems += [f"{k} = {setting_problem(k, v)}" for k, v in marker.kwargs.items()
                 if k in SETTINGS and setting_problem(k, v)]
    if problems:
        raise pytest.fail.Exception(f"@pytest.mark.{MARKER}(): {'; '.join(problems)}", pytrace=False)
    return {**settings, **{k: _setting(k, v) for k, v in marker.kwargs.items()}}


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    """A failing test's report gains the ``biotac`` section — inside its traceback's representation where it has one,
    so that JUnit XML's ``<failure>`` text holds it too, else beside it; after the call the text is also the test's
    property ``biotac`` (JUnit XML); after the teardown what the test made is no longer held (:data:`MADE`)."""
    report = yield
    text = description(item)
    if text is not None:
        if report.failed:
            title = f"Captured biotac {report.when}"
            if hasattr(report.longrepr, "addsection"):  # a traceback: printed with it, and in JUnit's <failure>
                report.longrepr.addsection(title, text)
            else:  # a one-line failure (pytest.fail(pytrace=False)): a section of the report
                report.sections.append((title, text))
        if report.when == "call":
            item.user_properties.append(("biotac", text))
    if report.when == "teardown" and MADE in item.stash:  # described for the last time: what the test made is let
        del item.stash[MADE]  # go (pytest keeps every item to the session's end, and every sensor and bench it held)
    return report

"""The claims' core: a ``Claim`` (one published figure, measured, with its kind and source), the ``Bench``
that acquires codes through the host's path, the group registry filled by ``@claim_group``, and the runner
and table.

Every claim says what kind of evidence it is (``kind``):

* ``prediction``  — follows from inputs that were not set to the figure being checked;
* ``calibrated``  — a model knob was tuned to reproduce this figure (``calibration`` names the knob and
  the target), so passing shows the tuning still holds, not that the physics predicts it;
* ``derived``     — arithmetic from other published inputs (or the same number as another row in other
  units);
* ``consistency`` — reads back a parameter set to the published value, evaluates a published formula, or
  cannot fail for physics reasons (``note`` says which): a regression check, not proof.
"""

from __future__ import annotations

import importlib
from dataclasses import asdict, dataclass, field
from typing import Callable

import numpy as np

from bench.running.sampler import Sampler
from emulator import conversions as conv
from emulator.channels import channel_index
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.spi.peripheral import SoftwarePeripheral

KINDS = ("prediction", "calibrated", "derived", "consistency")


@dataclass
class Claim:
    """One published figure: what was expected, what was measured, the accepted range, and what kind of
    evidence the row is (see the module docstring)."""

    name: str
    expected: str
    measured: float
    low: float
    high: float
    unit: str
    source: str  # where the figure is published: D section or table, or SENSOR.md §
    details: dict = field(default_factory=dict)
    kind: str = field(default="", kw_only=True)
    calibration: str = field(default="", kw_only=True)  # calibrated rows: the knob and what it was tuned to
    note: str = field(default="", kw_only=True)  # why the row has its kind (e.g. why it cannot fail)
    #: a published figure the model does not reproduce, and why: the row is reported (DEVIATES), not hidden,
    #: and the suite insists it still fails — a deviation that starts passing must be looked at again
    deviation: str = field(default="", kw_only=True)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"claim {self.name!r}: kind = {self.kind!r}; must be one of {', '.join(KINDS)}")
        if self.kind == "calibrated" and not self.calibration:
            raise ValueError(f"claim {self.name!r} is calibrated: name the knob and its target in calibration=")
        if not self.source:
            raise ValueError(f"claim {self.name!r}: give its source (D section or table, SENSOR.md §)")

    @property
    def passed(self) -> bool:
        return bool(np.isfinite(self.measured) and self.low <= self.measured <= self.high)

    @property
    def ok(self) -> bool:
        """Passes, or fails exactly as its documented deviation says."""
        return self.passed != bool(self.deviation)

    @property
    def result(self) -> str:
        if self.deviation:
            return "DEVIATES" if not self.passed else "PASS (deviation documented: recheck)"
        return "PASS" if self.passed else "FAIL"

    @property
    def tolerance(self) -> str:
        return f"[{self.low:.4g}, {self.high:.4g}]"

    def as_dict(self) -> dict:
        d = asdict(self)
        d.update(passed=self.passed, ok=self.ok, result=self.result, tolerance=self.tolerance)
        return d


@dataclass
class Bench:
    """Shared settings of one claims run."""

    fidelity: str = "default"
    seed: int = 2012
    params: SensorParams = field(default_factory=SensorParams)
    quick: bool = False  # fewer drops and hours, for a fast look (the suite never uses it)
    #: where a group that runs a campaign of its own (:data:`STARTS_A_CLUSTER`) runs it: a
    #: :class:`~bench.campaigns.engine.ClusterSpec`, or None for DASK_SCHEDULER_ADDRESS or else a LocalCluster
    cluster: object | None = None

    def acquire(self, stimuli, duration_s, sequence=("PAC", "PDC"), slot_rate_Hz=4400.0,
                noise=NoiseSources(), seed_offset=0) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Codes per channel through sensor -> SPI -> host; returns {name: (times, codes as float)}."""
        sensor = Sensor(self.params, stimuli, sequence, self.fidelity, self.seed + seed_offset, noise)
        sampler = Sampler(SoftwarePeripheral(sensor), list(sequence), slot_rate_Hz)
        chunks = list(sampler.chunks(int(round(duration_s * slot_rate_Hz)), int(slot_rate_Hz)))
        bad = sum(np.count_nonzero(c.status) for c in chunks)
        if bad:
            raise RuntimeError(f"the host saw {bad} bad words in a clean acquisition")
        times = np.concatenate([c.times for c in chunks])
        chans = np.concatenate([c.channels for c in chunks])
        codes = np.concatenate([c.codes for c in chunks]).astype(float)
        return {n: (times[chans == channel_index(n)], codes[chans == channel_index(n)]) for n in set(sequence)}

    def analog_pac_bits(self, stimuli, duration_s, rate_Hz=2200.0, noise=NoiseSources.none()):
        """PAC before the ADC, in LSB, sampled at ``rate_Hz``."""
        sensor = Sensor(self.params, stimuli, ("PAC",), self.fidelity, self.seed, noise)
        t = np.arange(int(round(duration_s * rate_Hz))) / rate_Hz
        return t, sensor.analog_trace("PAC", t) / conv.ADC_LSB_V


ClaimGroup = Callable[[Bench], list[Claim]]

#: group name -> function(bench) -> claims, in registration order (the table's order)
CLAIM_GROUPS: dict[str, ClaimGroup] = {}
#: group name -> function(sensor parameters) -> why the group cannot judge that sensor (a problem each; [] when it
#: can): a group whose accepted ranges derive from the sensor's parameters refuses those that would invert them
GROUP_REFUSALS: dict[str, Callable[[SensorParams], list[str]]] = {}


def claim_group(name: str, refuses: Callable[[SensorParams], list[str]] | None = None
                ) -> Callable[[ClaimGroup], ClaimGroup]:
    """Register a function ``f(bench) -> list[Claim]`` as the claim group ``name``; ``refuses(params)``, if given,
    says why the group cannot judge a sensor (:func:`check_sensor` asks it before anything runs)."""

    def register(fn: ClaimGroup) -> ClaimGroup:
        if name in CLAIM_GROUPS and CLAIM_GROUPS[name] is not fn:
            raise ValueError(f"claim group {name!r} is registered twice")
        CLAIM_GROUPS[name] = fn
        if refuses is not None:
            GROUP_REFUSALS[name] = refuses
        return fn

    return register


def check_sensor(params: SensorParams, groups) -> None:
    """ValueError, one line naming each parameter, its value and why, if a group of ``groups`` cannot judge the
    sensor ``params`` (:data:`GROUP_REFUSALS`): refused before any claim runs, rather than rows whose accepted
    range is inverted."""
    problems = [f"the {g} claims cannot judge this sensor: {p}" for g in groups for p in
                GROUP_REFUSALS.get(g, lambda _: [])(params)]
    if problems:
        raise ValueError("; ".join(problems) + " (leave the group out, --only, or change the sensor)")


def run_claims(bench: Bench, groups=None, progress=None) -> list[Claim]:
    """Every claim of ``groups`` (default: all) on ``bench``, after :func:`check_sensor`."""
    check_sensor(bench.params, list(groups or CLAIM_GROUPS))
    out = []
    for name in groups or CLAIM_GROUPS:
        if progress:
            progress(name)
        out += CLAIM_GROUPS[name](bench)
    return out


def kind_counts(claims: list[Claim]) -> dict[str, int]:
    return {k: sum(c.kind == k for c in claims) for k in KINDS}


def format_table(claims: list[Claim]) -> str:
    w = max(len(c.name) for c in claims)
    ws = max(6, max(len(c.source) for c in claims))
    lines = [f"{'claim':{w}s}  {'kind':11s} {'source':{ws}s}  {'expected':22s} {'measured':>12s} {'unit':10s} "
             f"{'accepted':22s} result"]
    for c in claims:
        lines.append(f"{c.name:{w}s}  {c.kind:11s} {c.source:{ws}s}  {c.expected:22s} {c.measured:12.4g} "
                     f"{c.unit:10s} {c.tolerance:22s} {c.result}")
    n_dev = sum(bool(c.deviation) and not c.passed for c in claims)
    n_fail = sum(not c.ok for c in claims)
    lines.append(f"{len(claims) - n_fail - n_dev} passed, {n_fail} failed, {n_dev} known deviations from the "
                 f"dissertation")
    for c in claims:
        if c.deviation and not c.passed:
            lines.append(f"  deviation: {c.name}: {c.deviation}")
    lines.append("kinds: " + ", ".join(f"{n} {k}" for k, n in kind_counts(claims).items()))
    return "\n".join(lines)


@dataclass
class Spread:
    """One claim over several seeds: its measured value per seed, whether it passed, and whether it held (passed,
    or failed exactly as its documented deviation says)."""

    name: str
    kind: str
    source: str
    expected: str
    unit: str
    low: float
    high: float
    seeds: list[int]
    measured: list[float]
    passed: list[bool]
    ok: list[bool] = field(default_factory=list)
    deviation: str = ""

    @property
    def min(self) -> float:
        return float(np.min(self.measured))

    @property
    def max(self) -> float:
        return float(np.max(self.measured))

    @property
    def failed_seeds(self) -> list[int]:
        """Seeds for which the claim did not hold (for a documented deviation: seeds for which it passed)."""
        held = self.ok or [p != bool(self.deviation) for p in self.passed]
        return [s for s, ok in zip(self.seeds, held) if not ok]

    def as_dict(self) -> dict:
        d = asdict(self)
        d.update(min=self.min, max=self.max, failed_seeds=self.failed_seeds,
                 tolerance=f"[{self.low:.4g}, {self.high:.4g}]")
        return d


#: Claim groups that start a Dask cluster of their own, so they cannot run as a task on a Dask worker (a worker
#: process cannot start worker processes): ``exploration`` runs the texture experiment through
#: ``bench.experiments.experiment.run_experiment``, which connects to a cluster even when every stage is cached.
#: Over seeds they run on the client, one after another, after the other groups' tasks (and their cluster) are done.
STARTS_A_CLUSTER = frozenset({"exploration"})


@dataclass(frozen=True)
class ClaimTask:
    """One claim group for one seed, as a campaign-engine task: the group's name (a worker finds it in its own
    registry) and the Bench it runs with (its seed among the settings)."""

    bench: Bench
    group: str

    def __repr__(self) -> str:  # how a failed task is named (the Bench's parameters are long)
        return f"ClaimTask(seed={self.bench.seed}, group={self.group!r})"


def run_claim_task(task: ClaimTask) -> list[dict]:
    """The engine's task: the group's claims as plain data, what a :class:`Spread` row takes from each."""
    importlib.import_module(__package__)  # in a worker: every shipped group registers itself
    return [{"name": c.name, "kind": c.kind, "source": c.source, "expected": c.expected, "unit": c.unit,
             "low": c.low, "high": c.high, "deviation": c.deviation, "measured": float(c.measured),
             "passed": c.passed, "ok": c.ok} for c in CLAIM_GROUPS[task.group](task.bench)]


def runs_on_workers(group: str) -> bool:
    """Whether ``group`` can run as a task on a Dask worker: a shipped group (one that importing this package
    registers, as a worker does), and one that starts no cluster of its own (:data:`STARTS_A_CLUSTER`).  A group
    registered at run time (a test's, a plugin's) is unknown to the workers: it runs on the client."""
    return (group not in STARTS_A_CLUSTER
            and CLAIM_GROUPS[group].__module__.startswith(__package__ + "."))


def run_claims_over_seeds(make_bench: Callable[[int], Bench], seeds, groups=None, progress=None, spec=None,
                          client=None) -> list[Spread]:
    """Run the claims once per seed (``make_bench(seed)``) and gather each claim's values across the seeds, in the
    order the seeds and groups are given.  Each (seed, group) pair is a task on the campaign engine (``spec``: a
    :class:`~bench.campaigns.engine.ClusterSpec`, default from the environment; or a connected ``client``), so two
    workers share even one seed's groups; groups that cannot run on a worker (:func:`runs_on_workers`) run here
    afterwards, each announced through ``progress(text)``.  ``progress`` also turns the engine's progress bar on."""
    from bench.campaigns.engine import run_tasks

    groups = list(groups or CLAIM_GROUPS)
    tasks = [ClaimTask(make_bench(seed), group) for seed in seeds for group in groups]
    for task in tasks:
        check_sensor(task.bench.params, [task.group])
    on_workers = [i for i, t in enumerate(tasks) if runs_on_workers(t.group)]
    found = dict(zip(on_workers, run_tasks(run_claim_task, [tasks[i] for i in on_workers], spec=spec,
                                           client=client, progress=progress is not None, desc="claim groups")))
    rows: dict[str, Spread] = {}
    for i, task in enumerate(tasks):
        if i not in found:
            if progress:
                progress(f"seed {task.bench.seed}: {task.group}")
            found[i] = run_claim_task(task)
        for c in found[i]:
            r = rows.setdefault(c["name"], Spread(c["name"], c["kind"], c["source"], c["expected"], c["unit"],
                                                  c["low"], c["high"], [], [], [], [], c["deviation"]))
            r.seeds.append(task.bench.seed)
            r.measured.append(c["measured"])
            r.passed.append(c["passed"])
            r.ok.append(c["ok"])
    return list(rows.values())


def format_spread_table(rows: list[Spread]) -> str:
    w = max(len(r.name) for r in rows)
    lines = [f"{'claim':{w}s}  {'kind':11s} {'expected':22s} {'min':>10s} {'max':>10s} {'unit':10s} "
             f"{'accepted':22s} seeds passed"]
    for r in rows:
        verdict = f"{sum(r.passed)}/{len(r.passed)}"
        if r.deviation:
            verdict += " (documented deviation)"
            if r.failed_seeds:
                verdict += " passes for seed " + ", ".join(map(str, r.failed_seeds)) + ": recheck it"
        elif r.failed_seeds:
            verdict += " (fails for seed " + ", ".join(map(str, r.failed_seeds)) + ")"
        accepted = f"[{r.low:.4g}, {r.high:.4g}]"
        lines.append(f"{r.name:{w}s}  {r.kind:11s} {r.expected:22s} {r.min:10.4g} {r.max:10.4g} {r.unit:10s} "
                     f"{accepted:22s} {verdict}")
    seeds = rows[0].seeds if rows else []
    bad = sum(bool(r.failed_seeds) for r in rows)
    dev = sum(bool(r.deviation) and not r.failed_seeds for r in rows)
    lines.append(f"{len(rows) - bad - dev} of {len(rows)} claims pass for every seed"
                 + (f", {dev} deviate as documented for every seed" if dev else "")
                 + f" ({', '.join(map(str, seeds))})")
    return "\n".join(lines)

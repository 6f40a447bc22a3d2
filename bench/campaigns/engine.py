"""The campaign engine: independent tasks run on Dask distributed, results in task order.

``run_tasks(fn, tasks)`` maps a pure, module-level function over task descriptions on a ``dask.distributed``
cluster: an in-process ``LocalCluster`` by default (one single-threaded worker process per core), or an existing
scheduler given by address (``scheduler="tcp://host:8786"`` or the ``DASK_SCHEDULER_ADDRESS`` environment
variable).  Each task carries its own seed (derived from its identity, never from the worker), so results are
identical for any number of workers and any scheduling order.  A worker that dies mid-task loses nothing: Dask
reschedules the task (``retries`` covers tasks that raise).  A progress bar runs on the client.

Short tasks travel in groups: each Dask task runs up to :data:`MAX_GROUP` consecutive tasks, so a rig trial of
~40 ms does not pay the scheduler's few milliseconds a round trip on its own, while every worker still gets at least
:data:`GROUPS_PER_WORKER` groups to balance the load.  Grouping changes nothing in the results (each task keeps
its own seed); a failing task is still reported by its own index.

Ctrl-C reaches only the client: a terminal sends SIGINT to the whole process group, and a LocalCluster's worker
processes (Python, each with its own event loop) would each die with a KeyboardInterrupt traceback.  They start
with SIGINT blocked (:func:`sigint_blocked`), so the client's KeyboardInterrupt alone closes the cluster, which
stops the workers quietly.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import signal
import sys
from dataclasses import dataclass
from typing import Callable, Sequence

import time as _time

#: when this module was imported, and the modules loaded before it (see :func:`stale_sources`): taken before this
#: module imports any of the project's own
_IMPORTED_AT = _time.time()
_LOADED_BEFORE = frozenset(sys.modules) - {__name__}

from bench.errors import BenchError  # noqa: E402 (after the snapshot above)
from bench.tomlfile import spelled  # noqa: E402


class CampaignError(BenchError, RuntimeError):
    """A campaign could not run (no cluster at the address) or a task failed after its retries."""


@dataclass(frozen=True)
class ClusterSpec:
    """Where tasks run: an existing scheduler's address, or a LocalCluster of ``workers`` processes."""

    scheduler: str | None = None
    workers: int | None = None

    @classmethod
    def from_env(cls, scheduler: str | None = None, workers: int | None = None) -> "ClusterSpec":
        """``scheduler`` (checked), else ``DASK_SCHEDULER_ADDRESS`` (checked), else a LocalCluster of ``workers``."""
        if scheduler:
            if workers is not None:
                raise ValueError(f"--workers {workers} sizes the LocalCluster this command would start; an existing "
                                 f"cluster (--scheduler {scheduler}) runs on its own workers: give one or the other")
            return cls(check_address(scheduler, "--scheduler"), workers)
        env = os.environ.get("DASK_SCHEDULER_ADDRESS")
        return cls(check_address(env, "DASK_SCHEDULER_ADDRESS") if env else None, workers)

    def describe(self) -> str:
        return f"scheduler {self.scheduler}" if self.scheduler else f"LocalCluster, {self.n_workers} worker(s)"

    @property
    def n_workers(self) -> int:
        return self.workers or max(1, os.cpu_count() or 1)


#: a scheduler address: [protocol://]host:port (a host name, an IPv4 address or a bracketed IPv6 one)
_ADDRESS = re.compile(r"^(?:(tcp|tls|ws|wss|ucx)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):(\d{1,5})$")


def check_address(text: str, where: str) -> str:
    """``text`` if it is a Dask scheduler's address (``tcp://HOST:PORT``, or ``HOST:PORT``), else ValueError naming
    ``where`` (the flag or the environment variable) — instead of distributed's words about a port, later."""
    m = _ADDRESS.match(text.strip())
    if not m or not 0 < int(m.group(3)) < 65536:
        raise ValueError(f"{where} {spelled(text)}: not a scheduler address; give tcp://HOST:PORT (the scheduler "
                         f"prints its own, e.g. tcp://10.0.0.5:8786)")
    return text.strip()


@contextlib.contextmanager
def signals_held():
    """Within the block SIGINT and SIGTERM are noted, not acted on (main thread only); the first that arrived is
    delivered after the block to the handler then in place (KeyboardInterrupt, :class:`~bench.cli.args.Terminated`,
    or the default) — unless an exception is already propagating: a stop under way keeps its first signal."""
    from bench.running.signals import signals_deferred

    with signals_deferred() as seen:
        yield
    if seen and sys.exc_info()[1] is None:
        signal.raise_signal(seen[0])


@contextlib.contextmanager
def sigint_blocked():
    """Block SIGINT in the calling thread within the block.  Threads started meanwhile (a LocalCluster's event
    loop) and the processes they spawn — the workers, now and on any later restart — inherit the blocked mask,
    also across exec, so they never see a Ctrl-C.  A SIGINT (or SIGTERM) to this process meanwhile is held, not
    lost, even when another thread (tqdm's monitor) takes it: it is delivered when the block ends
    (:func:`signals_held`)."""
    from multiprocessing import resource_tracker

    # multiprocessing launches its resource tracker at the first spawn and unblocks SIGINT in the launching thread
    # afterwards — that would be the cluster's thread, and the workers would inherit the unblocked mask; launched
    # here first (it ignores SIGINT itself), it leaves the mask alone
    resource_tracker.ensure_running()
    with signals_held():  # a signal the kernel gives another thread runs the (noting) handler in this one
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            yield
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)  # a SIGINT pending here is noted as it is unblocked


def connect(spec: ClusterSpec):
    """A ``distributed.Client`` for ``spec`` (the caller closes it; closing also stops a LocalCluster)."""
    from distributed import Client, LocalCluster

    if spec.workers is not None and spec.workers < 1:
        raise CampaignError(f"--workers = {spec.workers}: must be at least 1")
    if spec.scheduler:
        try:
            client = Client(spec.scheduler, timeout="5s")
        except (OSError, TimeoutError) as e:
            raise CampaignError(f"no Dask scheduler answers at {spec.scheduler}: {e}") from None
        except Exception as e:  # a protocol this client cannot speak as configured (tls:// without certificates, ucx)
            raise CampaignError(f"cannot connect to the Dask scheduler at {spec.scheduler}: {type(e).__name__}: {e} "
                                f"(tcp://HOST:PORT needs no configuration; tls:// needs the cluster's certificates in "
                                f"Dask's configuration, distributed.comm.tls)") from None
        try:  # a worker that cannot even run the check (an older bench.campaigns.engine, say) runs other code too
            stale = {w: files if isinstance(files, list) else [f"{type(files).__name__}: {files}"]
                     for w, files in client.run(stale_sources, on_error="return").items()
                     if not isinstance(files, list) or files}
        except BaseException:
            client.close()
            raise
        if stale:
            client.close()
            worker, files = next(iter(stale.items()))
            raise CampaignError(f"{len(stale)} worker(s) of the Dask scheduler at {spec.scheduler} hold modules of "
                                f"this project whose files changed after the worker started (e.g. {worker}: "
                                f"{', '.join(files[:3])}{', …' if len(files) > 3 else ''}), so they may run the old "
                                f"code; restart the workers (dask worker ...) and run again") from None
        if not client.scheduler_info().get("workers"):  # the tasks would wait, the progress bar at 0, saying nothing
            print(f"note: the Dask scheduler at {spec.scheduler} has no workers yet: the tasks wait until one joins "
                  f"(dask worker {spec.scheduler})", file=sys.stderr, flush=True)
        return client
    # no dashboard; the scheduler's small HTTP server takes any free port (not 8787, which another campaign or
    # notebook on this machine may hold: that only made distributed warn)
    cluster = client = None
    try:
        with sigint_blocked():  # the workers never see Ctrl-C: only the client does, and closes the cluster
            cluster = LocalCluster(n_workers=spec.n_workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None, scheduler_kwargs={"dashboard_address": ":0"},
                                   silence_logs=logging.CRITICAL)
            client = Client(cluster)
    except BaseException:  # a failed start, or a signal held during it (delivered as the block ends)
        _close_parts(client, cluster)
        raise
    client._owned_cluster = cluster  # closed with the client
    return client


#: the project's packages, whose modules a worker must run as they are on disk
PROJECT_PACKAGES = ("bench", "emulator")


def _process_start_time() -> float:
    """When this process started (epoch s), to the clock tick: from its start in ticks after boot (Linux); psutil's
    figure elsewhere, whose boot time is whole seconds (a file written in the second before the start could count
    as changed after it)."""
    import time

    try:
        with open("/proc/self/stat") as fh:
            ticks = int(fh.read().rsplit(")", 1)[1].split()[19])  # field 22, starttime (fields 3.. follow the name)
        return time.time() - (time.clock_gettime(time.CLOCK_BOOTTIME) - ticks / os.sysconf("SC_CLK_TCK"))
    except (OSError, ValueError, IndexError, AttributeError):
        import psutil

        return psutil.Process().create_time()


def stale_sources() -> list[str]:
    """The project's modules this process loaded whose source file changed after the process started (run on each
    worker of an existing cluster: a long-lived worker keeps running the code it imported, so its results — and the
    stage cache that stores them under the new code's digest — would silently come from the old code)."""
    # (a file written just before the start — by a script that then starts the worker — is not counted: the start
    # is known to a clock tick, and a worker imports nothing of the project in its first tenth of a second)
    started = _process_start_time() + 0.1
    # each module is compared with the earliest instant it can have been loaded at: the start for those loaded
    # before this module; for the others, this module's import or the check before the one that first listed them
    # (a fresh worker imports this module, and what it imports, to run this check: comparing those with the
    # process's start refused a worker that had loaded them after an edit, i.e. the new code)
    now = _time.time()
    out = []
    for name, module in list(sys.modules.items()):
        path = getattr(module, "__file__", None)
        if name.split(".")[0] not in PROJECT_PACKAGES or not path:
            continue
        if name not in _LOADED_BEFORE:
            _FIRST_LISTED.setdefault(name, _CHECKED_AT.get("last", _IMPORTED_AT))
        loaded_after = max(started, _FIRST_LISTED.get(name, started))
        try:
            if os.stat(path).st_mtime > loaded_after:
                out.append(path)
        except OSError:
            continue  # deleted or moved: no longer the code this process will see either
    _CHECKED_AT["last"] = now
    return sorted(out)


#: the earliest instant each module loaded after this one can have been loaded at, and the last check's instant
_FIRST_LISTED: dict[str, float] = {}
_CHECKED_AT: dict[str, float] = {}


def _close_parts(*parts) -> None:
    """Close each part that exists, with SIGINT and SIGTERM held meanwhile: a second Ctrl-C would only interrupt
    the closing and make the exit wait out distributed's timeouts (~10 s instead of ~1 s)."""
    with signals_held():
        for part in parts:
            if part is not None:
                part.close()


def close(client) -> None:
    """Close ``client`` and the LocalCluster :func:`connect` started for it, if any.  A client that lost its
    scheduler logs the cancelled reconnection as a traceback while it closes: the bench has said what happened in
    one line (:func:`run_tasks`), so the client's log is held to critical errors meanwhile."""
    log = logging.getLogger("distributed.client")
    level = log.level
    log.setLevel(logging.CRITICAL)
    try:
        _close_parts(client, getattr(client, "_owned_cluster", None))
    finally:
        log.setLevel(level)


#: at most this many tasks per Dask task (a group of rig trials lasts well under a second)
MAX_GROUP = 16
#: at least this many groups per worker thread, so that no worker waits long for the last group
GROUPS_PER_WORKER = 8


class TaskFailed(Exception):
    """A task of a group raised: ``args`` = (its index in the campaign, what it raised, in words)."""


def _run_group(fn: Callable, first: int, group: list) -> list:
    """``[fn(t) for t in group]``; a failure names the task's campaign index (``first`` + position)."""
    out = []
    for k, task in enumerate(group):
        try:
            out.append(fn(task))
        except Exception as e:
            raise TaskFailed(first + k, f"{type(e).__name__}: {e}") from None
    return out


def group_size(n_tasks: int, n_threads: int) -> int:
    """Tasks per group: at most :data:`MAX_GROUP`, and few enough for :data:`GROUPS_PER_WORKER` groups a thread."""
    return max(1, min(MAX_GROUP, n_tasks // (max(1, n_threads) * GROUPS_PER_WORKER)))


def run_tasks(fn: Callable, tasks: Sequence, spec: ClusterSpec | None = None, client=None, progress: bool = True,
              desc: str = "tasks", retries: int = 2, on_result: Callable | None = None) -> list:
    """``[fn(t) for t in tasks]`` on the cluster, in task order. ``fn`` must be importable by the workers (a
    module-level function) and pure: its result may depend only on its task.  ``on_result(index, result)`` is
    called for each task as its result arrives (in the order they finish): a caller stopped by Ctrl-C or a lost
    cluster keeps what had finished."""
    from distributed import as_completed
    from tqdm import tqdm

    if not tasks:
        return []
    own = client is None
    client = client or connect(spec or ClusterSpec.from_env())
    try:
        tasks = list(tasks)
        size = group_size(len(tasks), sum(client.nthreads().values()))
        futures = [client.submit(_run_group, fn, i, tasks[i:i + size], pure=False, retries=retries)
                   for i in range(0, len(tasks), size)]
        first = {f.key: i * size for i, f in enumerate(futures)}
        results: list = [None] * len(tasks)
        with tqdm(total=len(tasks), desc=desc, unit="task", disable=not progress) as bar:
            for fut in as_completed(futures):
                i = first[fut.key]
                try:
                    done = fut.result()
                except Exception as e:  # a task that kept failing after its retries, or a group lost for good
                    for f in futures:
                        f.cancel()
                    if getattr(e, "reason", None) == "scheduler-connection-lost":  # no task failed: the cluster went
                        raise CampaignError(
                            f"lost the connection to the Dask scheduler at {client.scheduler.address} after {bar.n} "
                            f"of {len(tasks)} tasks had finished; start the scheduler and its workers again and run "
                            f"again (an experiment's finished stages are in its cache)") from None
                    k, what = e.args if isinstance(e, TaskFailed) else (i, f"{type(e).__name__}: {e}")
                    raise CampaignError(f"task {k} ({tasks[k]!r}) failed: {what}") from None
                results[i:i + len(done)] = done
                if on_result is not None:
                    for k, result in enumerate(done):
                        on_result(i + k, result)
                bar.update(len(done))
        return results
    finally:
        if own:
            close(client)

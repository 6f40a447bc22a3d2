"""The campaign engine: independent tasks run on Dask distributed, results in task order.

``run_tasks(fn, tasks)`` maps a pure, module-level function over task descriptions on a ``dask.distributed``
cluster: an in-process ``LocalCluster`` by default (one single-threaded worker process per core), or an existing
scheduler given by address (``scheduler="tcp://host:8786"`` or the ``DASK_SCHEDULER_ADDRESS`` environment
variable).  Each task carries its own seed (derived from its identity, never from the worker), so results are
identical for any number of workers and any scheduling order.  A worker that dies mid-task loses nothing: Dask
reschedules the task (``retries`` covers tasks that raise).  A progress bar runs on the client.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass
from typing import Callable, Sequence

from bench.errors import BenchError


class CampaignError(BenchError, RuntimeError):
    """A campaign could not run (no cluster at the address) or a task failed after its retries."""


@dataclass(frozen=True)
class ClusterSpec:
    """Where tasks run: an existing scheduler's address, or a LocalCluster of ``workers`` processes."""

    scheduler: str | None = None
    workers: int | None = None

    @classmethod
    def from_env(cls, scheduler: str | None = None, workers: int | None = None) -> "ClusterSpec":
        return cls(scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS") or None, workers)

    def describe(self) -> str:
        return f"scheduler {self.scheduler}" if self.scheduler else f"LocalCluster, {self.n_workers} worker(s)"

    @property
    def n_workers(self) -> int:
        return self.workers or max(1, os.cpu_count() or 1)


def connect(spec: ClusterSpec):
    """A ``distributed.Client`` for ``spec`` (the caller closes it; closing also stops a LocalCluster)."""
    from distributed import Client, LocalCluster

    if spec.workers is not None and spec.workers < 1:
        raise CampaignError(f"--workers = {spec.workers}: must be at least 1")
    if spec.scheduler:
        try:
            return Client(spec.scheduler, timeout="5s")
        except (OSError, TimeoutError) as e:
            raise CampaignError(f"no Dask scheduler answers at {spec.scheduler}: {e}") from None
    # no dashboard; the scheduler's small HTTP server takes any free port (not 8787, which another campaign or
    # notebook on this machine may hold: that only made distributed warn)
    cluster = LocalCluster(n_workers=spec.n_workers, threads_per_worker=1, processes=True, dashboard_address=None,
                           scheduler_kwargs={"dashboard_address": ":0"}, silence_logs=logging.CRITICAL)
    client = Client(cluster)
    client._owned_cluster = cluster  # closed with the client
    return client


def close(client) -> None:
    cluster = getattr(client, "_owned_cluster", None)
    client.close()
    if cluster is not None:
        cluster.close()


def run_tasks(fn: Callable, tasks: Sequence, spec: ClusterSpec | None = None, client=None, progress: bool = True,
              desc: str = "tasks", retries: int = 2) -> list:
    """``[fn(t) for t in tasks]`` on the cluster, in task order. ``fn`` must be importable by the workers (a
    module-level function) and pure: its result may depend only on its task."""
    from distributed import as_completed
    from tqdm import tqdm

    if not tasks:
        return []
    own = client is None
    client = client or connect(spec or ClusterSpec.from_env())
    try:
        futures = client.map(fn, list(tasks), pure=False, retries=retries)
        index = {f.key: i for i, f in enumerate(futures)}
        results: list = [None] * len(futures)
        with tqdm(total=len(futures), desc=desc, unit="task", disable=not progress) as bar:
            for fut in as_completed(futures):
                try:
                    results[index[fut.key]] = fut.result()
                except Exception as e:  # a task that kept failing after its retries
                    for f in futures:
                        f.cancel()
                    raise CampaignError(f"task {index[fut.key]} ({tasks[index[fut.key]]!r}) failed: "
                                        f"{type(e).__name__}: {e}") from None
                bar.update(1)
        return results
    finally:
        if own:
            close(client)

"""A campaign compiles the emulator's numba kernels before its cases, so no case's wall-clock waits include a compiler.

In a fresh clone (numba's cache empty) the kernels compiled inside a case's first firmware step: on a loaded machine
a sliding scene's took 24 s, longer than the 10 s a case waits for a frame, and its first ``none`` case failed with
"only 0 frames arrived" (it passed when run again).  Each test runs in a subprocess with a cache directory of its
own (``NUMBA_CACHE_DIR``), so it starts as a fresh clone does."""

import json
import os
import subprocess
import sys

import pytest

from bench.paths import REPO

pytestmark = pytest.mark.unit

#: the emulator's kernels: every numba dispatcher in an imported emulator module
KERNELS = """
import sys
from numba.core.registry import CPUDispatcher

def kernels():
    return [v for name, m in list(sys.modules.items()) if name.startswith("emulator") for v in vars(m).values()
            if isinstance(v, CPUDispatcher)]

def compiled():
    return sum(len(k.signatures) for k in kernels())
"""

#: a campaign on an in-process Dask cluster; each case records how many kernel signatures it compiled
CAMPAIGN = KERNELS + """
import json
from distributed import Client, LocalCluster
from bench.campaigns import faults

run_case, during = faults.run_case, []

def counted(*args, **kwargs):
    before = compiled()
    result = run_case(*args, **kwargs)
    during.append(compiled() - before)
    return result

faults.run_case = counted
with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as c, Client(c) as client:
    results = faults.run_campaign(["none", "serial_corruption"], ["taps"], [0], client=client)
print(json.dumps({"passed": [r["passed"] for r in results], "compiled_in_cases": during,
                  "compiled_before": compiled() - sum(during)}))
"""

#: one case in a process of its own: what it took from numba's cache on disk and what it had to compile
CASE = KERNELS + """
import json
from bench.campaigns import faults

result = faults.run_case(faults.FAULTS["none"], "taps", 1)
print(json.dumps({"passed": result["passed"], "hits": sum(sum(k.stats.cache_hits.values()) for k in kernels()),
                  "misses": sum(sum(k.stats.cache_misses.values()) for k in kernels())}))
"""


def _run(code: str, cache_dir) -> dict:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache_dir), "PYTHONPATH": str(REPO)}
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, env=env, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_campaign_compiles_every_kernel_its_cases_use_before_the_first_case_starts(tmp_path):
    campaign = _run(CAMPAIGN, tmp_path)
    assert campaign["passed"] == [True, True]
    assert campaign["compiled_before"] > 0  # from an empty cache: compiled before the first case
    assert campaign["compiled_in_cases"] == [0, 0]
    # a worker in another process on this machine takes them from numba's cache on disk, compiling nothing
    case = _run(CASE, tmp_path)
    assert case["passed"] and case["hits"] > 0 and case["misses"] == 0

"""FirmwareBench (the ``biotac_bridge`` fixture's bench) refuses a step or line-fault rate it cannot honour."""

import math

import pytest

from bench.hosts.bridge import FirmwareBench

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("kw, needle", [
    (dict(step_s=0), "step_s = 0: must be a number > 0"),  # had run: the firmware never advanced, no frame came
    (dict(step_s=-1.0), "step_s = -1.0"),
    (dict(step_s=math.nan), "step_s = nan"),
    (dict(corrupt_rate=2), "corrupt_rate = 2: must be a probability per byte, 0 to 1"),  # had corrupted every byte
    (dict(drop_rate=-1), "drop_rate = -1"),  # had been no fault at all
    (dict(corrupt_rate=math.nan), "corrupt_rate = nan"),
    (dict(corrupt_rate=0.6, drop_rate=0.6), "corrupt_rate + drop_rate = 1.2"),
])
def test_a_step_or_a_rate_the_bench_cannot_honour_is_refused(kw, needle):
    with pytest.raises(ValueError, match=needle.replace("+", r"\+")):
        FirmwareBench(**kw)

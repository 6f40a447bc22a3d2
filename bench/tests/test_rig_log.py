"""The rig's log: PAC and PDC kept apart as read are the samples of every read, filtered."""

from __future__ import annotations

import numpy as np

from bench.rigs.texture_rig import Movement, _Log
from bench.running.sampler import Samples
from emulator import channels as ch


def test_pac_and_pdc_kept_as_read_are_all_samples_read_filtered():
    """(consistency) The log's PDC codes, frame count and recording (PAC and PDC instants and codes) equal what
    filtering every sample read, concatenated, gives — over reads of uneven lengths, before and after a read."""
    rng = np.random.default_rng(5)
    log, start = _Log(), 0
    frame = np.array([ch.PAC, ch.PDC, ch.PAC, ch.TDC, ch.PAC, ch.ELECTRODE_FIRST], dtype=np.int64)
    for n in (12, 30, 6, 18):
        k = start + np.arange(n)
        channels = frame[k % frame.size]
        codes = rng.integers(0, 4096, n).astype(np.uint16)
        log.samples(Samples(k / 4400.0, channels, codes, codes, np.zeros(n, np.uint8)))
        log.current(k[::6] / 4400.0, rng.random(n // 6))
        start += n
        t, c, code = log._cat()
        np.testing.assert_array_equal(log.pdc_codes(), code[c == ch.PDC].astype(float))
        assert log.n_frames(frame.size) == t.size // frame.size
    rec = log.recording(0.0, 0.001, 0.01, 1, Movement(0.5, 0.025), 0, 1)
    t, c, code = log._cat()
    for got, expected in ((rec.pac_t, t[c == ch.PAC]), (rec.pac, code[c == ch.PAC]), (rec.pdc_t, t[c == ch.PDC]),
                          (rec.pdc, code[c == ch.PDC])):
        np.testing.assert_array_equal(got, expected)

"""The test bench around the emulated sensor, cut by concern (data flows top to bottom):

* :mod:`bench.scenes` — the scene format and its validation (what happens to the finger, what the host reads).
* :mod:`bench.running` — scene → sensor → SPI peripheral → host sampler, streamed in chunks.
* :mod:`bench.hosts` — things under test and their transports: firmware co-simulation, pty serial link, host
  driver, the Cheetah-compatible library's server, native builds.
* :mod:`bench.verification` — measurements and verdicts: analysis, published-figure claims, psychophysics,
  benchmarks.
* :mod:`bench.reporting` — records, reports and plots.
* :mod:`bench.campaigns` — many independent runs (fault campaigns).
* :mod:`bench.cli` — the ``biotac-bench`` command; :mod:`bench.pytest_plugin` — fixtures for users' tests.

Shared: :mod:`bench.errors` (the error root), :mod:`bench.paths` (shipped files and ``out/``). Nothing in
:mod:`emulator` imports from :mod:`bench`.
"""

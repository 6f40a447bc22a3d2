"""pytest plugin (entry point ``pytest11``, name ``biotac``): :mod:`.fixtures` hands users' tests an emulated sensor,
a bridge on a pty, or the Cheetah path; :mod:`.hooks` says in a failing test's report (and its JUnit property) what
those sensors were and felt, and adds ``--biotac-spi``."""

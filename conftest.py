"""Suite-wide set-up.

The Ctrl-C tests (a run, ``record`` and ``cheetah serve`` interrupted by SIGINT) need SIGINT to be deliverable.
A suite started as a background job of a non-interactive shell inherits SIGINT *ignored*, and so would every
command it starts, which then rightly keeps ignoring it; those tests would fail for a reason that is not the
code's.  Give the test process Python's default handler back (its children then start with SIGINT's default).
"""

import signal

if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

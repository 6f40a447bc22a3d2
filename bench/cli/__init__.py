"""The ``biotac-bench`` command line: :mod:`bench.cli.main` builds the parser from one module per command group.

Importing it limits BLAS to one thread per process unless the user chose otherwise: the emulator's matrix
products are tiny (the thermal network has a handful of nodes), so extra BLAS threads only spin on the other
core and double the CPU a run takes without shortening it (measured: a touched full frame at 309× real time in
CPU with the default threads, 617× with one, the same wall time).  Dask's worker processes get the same limit
from their nanny.  This runs before numpy is first imported by the command."""

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

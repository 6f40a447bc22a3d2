"""The ``biotac-bench`` command line: :mod:`bench.cli.main` builds the parser from one module per command group."""

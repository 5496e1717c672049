"""`bicycle-xval`: the command line (`main`), at the top of the package: nothing imports it."""

import os

# One BLAS thread per process, set before numpy is first imported (the Makefile sets the same):
# the matrices here are small (<= 500) and `run` already keeps both cores busy with worker
# processes. Threaded BLAS made them contend: `run --quick`'s two fault-injection stages took
# 6.2 s + 11.5 s with the default threads, 0.26 s + 1.26 s with one (2-core EPYC, one run
# each, other agents busy). A value the user set is kept.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
del _var

from .errors import EXIT_FAIL, EXIT_OK, EXIT_USAGE, UsageError
from .main import build_parser, main

__all__ = ["EXIT_FAIL", "EXIT_OK", "EXIT_USAGE", "UsageError", "build_parser", "main"]

"""`bicycle-xval`: the command line (`main`), at the top of the package: nothing imports it."""

from .errors import EXIT_FAIL, EXIT_OK, EXIT_USAGE, UsageError
from .main import build_parser, main

__all__ = ["EXIT_FAIL", "EXIT_OK", "EXIT_USAGE", "UsageError", "build_parser", "main"]

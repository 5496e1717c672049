"""Exit statuses and the user-mistake exception of the command line."""

EXIT_OK, EXIT_FAIL, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_TERMINATED = 0, 1, 2, 130, 143


class UsageError(Exception):
    """A user mistake: reported on one line, exit status 2."""

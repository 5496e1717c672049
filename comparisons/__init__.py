"""Scenarios, metrics, the runner, the report writer and the `bicycle-xval` command line."""

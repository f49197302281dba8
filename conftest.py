"""Test-session set-up: notebooks run under nbval write results/ into a temporary folder."""
import os
import tempfile


def pytest_configure(config):
    if "REPLICATION_RESULTS_DIR" not in os.environ:
        os.environ["REPLICATION_RESULTS_DIR"] = tempfile.mkdtemp(prefix="replication-results-")

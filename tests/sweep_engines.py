"""What the sweep tests share (tests/test_sweep.py, test_sweep_integrity.py,
test_sweep_processes.py): an in-process Dask cluster, and engines that misbehave on one
bicycle, written out as a plugin file (`hostile_engines`) so Dask's workers import them by
path like any third party's.
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

__all__ = ["HOSTILE", "hostile_engines", "local_client"]

HOSTILE = '''
import os
import time
from engines.base import Engine

class Killer(Engine):
    """The reference's M; ends its process (os._exit) for a rider lighter than 85 kg."""
    name = "killer"
    capabilities = frozenset({"mass_matrix"})

    def mass_matrix(self, q):
        if self.model.params.m3 < 85.0:
            os._exit(3)
        return self.model.mass_matrix(q)

class Freezer(Engine):
    """The reference's M; for a rider heavier than 85 kg it sleeps 600 s inside C *holding
    the interpreter lock* (a ctypes.PyDLL call keeps the GIL), as a C loop that never releases
    it would: its whole worker process freezes, threads and heartbeats included."""
    name = "freezer"
    capabilities = frozenset({"mass_matrix"})

    def mass_matrix(self, q):
        if self.model.params.m3 > 85.0:
            import ctypes
            ctypes.PyDLL(None).sleep(600)
        return self.model.mass_matrix(q)

class Sleeper(Engine):
    """The reference's M; hangs (sleeps 30 s) for a rider heavier than 85 kg."""
    name = "sleeper"
    capabilities = frozenset({"mass_matrix"})

    def mass_matrix(self, q):
        if self.model.params.m3 > 85.0:
            time.sleep(30.0)
        return self.model.mass_matrix(q)
'''


def hostile_engines(folder: Path) -> Path:
    """`HOSTILE` written to ``folder/hostile.py``: engines ``<path>:Killer``, ``<path>:Sleeper``,
    ``<path>:Freezer``."""
    path = Path(folder) / "hostile.py"
    path.write_text(HOSTILE)
    return path


@contextmanager
def local_client():
    """A Dask client of one in-process worker thread (no process to spawn: ~0.3 s)."""
    from distributed import Client, LocalCluster
    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                           dashboard_address=None, silence_logs=50)
    client = Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()

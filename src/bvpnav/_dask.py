"""Dask pieces of :mod:`bvpnav.batch` that must be importable by name in a worker process.

Imported only once ``dask.distributed`` is (``bvpnav[batch]``), by :func:`bvpnav.batch.run_batch`
when it starts its local cluster.
"""

from __future__ import annotations

import signal

from distributed import WorkerPlugin


class IgnoreCtrlC(WorkerPlugin):
    """Set SIGINT (Ctrl-C) to :data:`signal.SIG_IGN` in every worker process of a local cluster
    as it starts, including one that a nanny starts again after the first died.

    Ctrl-C in a terminal reaches the whole process group; only the process that runs the batch
    should act on it (by closing the cluster), not each worker with its own traceback. A worker
    started while the batch sets SIGINT to SIG_IGN inherits that, but a nanny restarts a dead
    worker later, from a process where Ctrl-C raises again; this plugin runs in each worker
    before it joins the scheduler, so no task runs in a worker that Ctrl-C interrupts.
    """

    name = "bvpnav-ignore-ctrl-c"

    def setup(self, worker) -> None:
        """Ignore SIGINT in this worker process (nothing to do off its main thread)."""
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        except ValueError:  # off the main thread: signals are not this thread's to change
            pass

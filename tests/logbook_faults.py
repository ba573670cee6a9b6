"""A folder run's task with faults in its way (``tests/test_logbook_batch.py``), in a module of its own:
each worker process imports it, and it imports next to nothing (the workers start in a second)."""

import os
import signal
from pathlib import Path


def faulty(path, root, out, filters=None, page=False):
    """``summarise``, except on the logs named for a fault; logs named "quick" give only their fields (a time limit of
    seconds is then no race with a loaded machine)."""
    from groundstation.logbook.summary import log_fields, summarise

    name = Path(path).name
    if "quick" in name:
        return [log_fields(Path(path), Path(root))]
    if name.startswith("raises"):
        raise RuntimeError("a defect met in this log")
    if name.startswith("dies"):
        os._exit(3)
    if name.startswith("stops"):
        os.kill(os.getpid(), signal.SIGSTOP)  # as a worker stopped from outside: it never ends on its own
    return summarise(path, root, out, filters, page)

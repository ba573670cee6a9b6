"""Python's garbage collector only in the GUI thread.

A file's loading thread (``session_makers.load.Loading``) allocates enough to start a collection; a cycle it
then frees may hold a closed window's Qt objects, whose C++ destructors run in that thread and wait for
the GUI thread (Shiboken's ``runDeletionInMainThread`` takes the GIL) while the GUI thread waits for the
GIL: a deadlock (seen with ``py-spy dump --native`` on two stuck test workers). pyqtgraph's
``GarbageCollector`` turns automatic collection off and collects on a timer in the GUI thread instead.
"""

from __future__ import annotations

from pyqtgraph.util.garbage_collector import GarbageCollector

_collector: GarbageCollector | None = None


def collect_in_gui_thread() -> None:
    """Once per process, from the GUI thread (the first window does it)."""
    global _collector
    if _collector is None:
        _collector = GarbageCollector(interval=1.0)

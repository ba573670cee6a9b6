"""The first start on a machine: numba's cache (``compiled_cache``) filled by another process.

A live session starts at once with the estimators whose kernels are in the cache, the others running
their kernel's source interpreted (``CompiledEstimator.ready_or_interpreted``; 0.03-0.15 ms a sample)
while another process compiles the kernels into the cache; each estimator goes on compiled, its state
kept, as its kernel arrives (``session_parts.estimators.EstimatorBank``). So these estimators have every sample
from the first: the session's tables are a batch run's within the 1e-12 that separates the interpreted
source from the compiled kernel, with no hole. The other way, a hole filled once compiled, would rewrite
rows the window has drawn, the plots' and a Foxglove client's. Only ukf and sssrukf, about 1 ms a sample
interpreted, wait (NaN rows) for their kernels, compiled last, and then run the samples they missed at
once, so that from there on they are what a batch run gives. Why a
process and not a thread: numba's compiler is Python and LLVM under the GIL, so a thread would share
our GIL for the whole 30 CPU s (the main thread's 10 ms tick paused up to 0.68 s while ahf2 compiled in
a thread, 0.06 s while it compiled in a process; the compile's CPU counted against us too:
bench/bench_first_data.out.md). Why not at install
time: a wheel has no post-install step, numba's ahead-of-time ``numba.pycc`` is deprecated and needs a C
compiler, and numba keys each cached kernel by the CPU it was made for: a cache shipped from another
machine is ignored and compiled anew. Only a cache made for a generic CPU (``NUMBA_CPU_NAME=generic``)
travels, and only to processes that name the generic CPU too, which then run about 5 % slower; it would
have to be built by us per platform and Python, or by ``pip install .`` (about 30 CPU s more, with no
hook to do it) (bench/bench_first_data.out.md).
"""

from __future__ import annotations

import multiprocessing
import multiprocessing.connection
import os
import signal
import threading


class WarmUp:
    """A process compiling estimators' kernels into numba's cache, in the order named. For a live session
    (``runs_first`` False) their per-sample kernels first (what it waits for), then their batch loops
    (what a later export or replay would compile); for a file opened whole (``runs_first``), each one's
    kernel and batch loop in turn, so that each estimator can join as soon as its ``run`` is ready.
    ``compiled`` holds the names whose per-sample kernel is in the cache, as the process says so, ``runs``
    those whose batch loop is too (``Estimator.runs_compiled``), ``finished`` once it ended;
    ``generation`` counts all three (a cheap "anything new?" for the reader thread and the window)."""

    def __init__(self, names, runs_first: bool = False):
        self.names = tuple(names)
        self.runs_first = runs_first
        self.compiled: set[str] = set()
        self.runs: set[str] = set()
        self.finished = False
        self.generation = 0
        context = multiprocessing.get_context("spawn")  # not fork: numba and Qt are not fork-safe; the bundle supports spawn
        receive, send = context.Pipe(duplex=False)
        self._process = context.Process(target=compile_kernels, args=(self.names, send, runs_first), name="groundstation-compile",
                                        daemon=True)
        self._start_without_ctrl_c()
        send.close()  # the child holds the other end: its exit ends ``_listen``
        self._listener = threading.Thread(target=self._listen, args=(receive,), name="groundstation-compile-listener", daemon=True)
        self._listener.start()

    def _start_without_ctrl_c(self) -> None:
        """Ctrl-C in a terminal goes to every process of its group: the child is born ignoring it (an ignored
        signal stays ignored across exec, and Python keeps it so), so it neither prints a traceback nor dies
        half-way; it ends with us (``daemon``; ``_exit_with_parent`` if we are killed)."""
        main = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
        try:
            self._process.start()
        finally:
            if main:
                signal.signal(signal.SIGINT, previous)

    def _listen(self, receive) -> None:
        with receive:
            while True:
                try:
                    name, batch_loop = receive.recv()
                except (EOFError, OSError):
                    break
                (self.runs if batch_loop else self.compiled).add(name)
                self.generation += 1
        self.finished = True  # done, or stopped: nothing more will come
        self.generation += 1

    @property
    def running(self) -> bool:
        return self._process.is_alive()

    def stop(self) -> None:
        """End the compiling process now (what it compiled stays in the cache; the rest compiles next time)."""
        if self._process.is_alive():
            self._process.terminate()
        self._process.join()


_warming: WarmUp | None = None  # the process's one compiler: two would compile the same kernels twice


def warm_up(names, runs_first: bool = False) -> WarmUp:
    """The background compiler of ``names``' kernels (``WarmUp``): the one running already if it compiles them
    all in an order that suits (a file's ``runs_first``), else a new one, ``names`` first, then what the one
    running had left (stopped: a file opened after a live start would wait for every per-sample kernel first)."""
    global _warming
    running = _warming is not None and _warming.running
    if running and set(names) <= set(_warming.names) and (_warming.runs_first or not runs_first):
        return _warming
    if running:
        _warming.stop()
        names = (*names, *(name for name in _warming.names if name not in names))
    _warming = WarmUp(names, runs_first)
    return _warming


def stop_warm_up() -> None:
    """The process's background compiler ended, if one runs (the app closing: it would take CPU from the close)."""
    if _warming is not None:
        _warming.stop()


def compile_kernels(names, send, runs_first: bool = False) -> None:
    """In the compiling process: each estimator's per-sample kernel, then each one's batch loop, into the
    cache (``runs_first``: each one's both in turn), said through ``send`` as ``(name, batch loop)`` as each is there."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # in case it was started from a thread other than the main one
    threading.Thread(target=_exit_with_parent, name="groundstation-parent-watch", daemon=True).start()
    import numpy as np

    from groundstation.estimation import create

    one = np.zeros((1, 3))

    def batch_loop(name):
        create(name).run(one, one, np.ones(1))  # compiles its batch loop (vqf: the guard's)
        send.send((name, True))

    for name in names:
        create(name)
        send.send((name, False))
        if runs_first:
            batch_loop(name)
    if not runs_first:
        for name in names:
            batch_loop(name)
    send.close()


def _exit_with_parent() -> None:
    """Our parent gone (killed, crashed) before we finished: stop compiling for nobody."""
    multiprocessing.connection.wait([multiprocessing.parent_process().sentinel])
    os._exit(0)

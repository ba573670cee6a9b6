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
    """A process compiling estimators' kernels into numba's cache, in the order named: their per-sample
    kernels first (what a live session waits for), then their batch loops (what a later export or
    replay would compile). ``compiled`` holds the names whose per-sample kernel is in the cache, as the
    process says so, ``finished`` once it ended; ``generation`` counts both (a cheap "anything new?" for the
    reader thread)."""

    def __init__(self, names):
        self.names = tuple(names)
        self.compiled: set[str] = set()
        self.finished = False
        self.generation = 0
        context = multiprocessing.get_context("spawn")  # not fork: numba and Qt are not fork-safe; the bundle supports spawn
        receive, send = context.Pipe(duplex=False)
        self._process = context.Process(target=compile_kernels, args=(self.names, send), name="groundstation-compile", daemon=True)
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
                    name = receive.recv()
                except (EOFError, OSError):
                    break
                self.compiled.add(name)
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


def warm_up(names) -> WarmUp:
    """The background compiler of ``names``' kernels: the one running already, else a new one."""
    global _warming
    if _warming is None or not _warming.running:
        _warming = WarmUp(names)
    return _warming


def compile_kernels(names, send) -> None:
    """In the compiling process: each estimator's per-sample kernel into the cache, said through ``send``
    as each is there; then each one's batch loop."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # in case it was started from a thread other than the main one
    threading.Thread(target=_exit_with_parent, name="groundstation-parent-watch", daemon=True).start()
    import numpy as np

    from groundstation.estimation import create

    for name in names:
        create(name)
        send.send(name)
    one = np.zeros((1, 3))
    for name in names:
        create(name).run(one, one, np.ones(1))  # compiles its batch loop (vqf: the guard's)
    send.close()


def _exit_with_parent() -> None:
    """Our parent gone (killed, crashed) before we finished: stop compiling for nobody."""
    multiprocessing.connection.wait([multiprocessing.parent_process().sentinel])
    os._exit(0)

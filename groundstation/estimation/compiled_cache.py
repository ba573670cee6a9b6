"""Where numba keeps the compiled estimators: a per-user cache folder, not ``__pycache__`` beside the sources.

numba's default cache sits in ``__pycache__`` next to each module, so re-installing the package (what
a test command that installs it does) deletes it and the next start compiles every kernel again
(about 30 CPU s). In the user's cache folder it survives a re-install. numba checks
each cached kernel against its own source file (a hash of the file's bytes, numba 0.68) but not the
modules it calls into ("Cache invalidation fails to recognize changes in symbols defined in a
different file", numba's notes on caching): the folder is therefore named by a hash of every estimation
source, so a change to any of them (``base.py``'s guard, a helper) starts a fresh folder.

``NUMBA_CACHE_DIR`` set by the user wins. Set just before numba is imported (numba reads it at import;
``use_user_cache_for_numba``: hashing the sources costs as much as a command's ``--help`` may in all,
bench/bench_help.py) and also on ``numba.config`` in case something imported numba first.

The first start on a machine (an empty cache) compiles in the background (``warm_up``): a live session
starts at once with the estimators whose kernels are in the cache, the others running their kernel's
source interpreted (``CompiledEstimator.ready_or_interpreted``; 0.03-0.15 ms a sample, ukf and sssrukf
about 1 ms), while another process compiles the kernels into the cache; each estimator goes on compiled,
its state kept, as its kernel arrives (``EstimatorBank``). So every estimator has every sample from the
first: the session's tables are a batch run's within the 1e-12 that separates the interpreted source
from the compiled kernel, with no hole to fill afterwards. Why a process and not a thread: numba's
compiler is Python and LLVM under the GIL, so a thread compiling the kernels (about 30 CPU s) would
stall the window and the reader thread for as long (bench/bench_first_data.out.md). Why not at install
time: a wheel has no post-install step, numba's ahead-of-time ``numba.pycc`` is deprecated and needs a C
compiler, and a cache made elsewhere is for that machine's CPU (numba keys each entry by CPU name and
features), so a shipped cache would be ignored on another CPU and compiled anyway.
"""

from __future__ import annotations

import hashlib
import multiprocessing
import multiprocessing.connection
import os
import signal
import sys
import threading
from pathlib import Path

ENV_VAR = "NUMBA_CACHE_DIR"
SOURCES = Path(__file__).resolve().parent  # the estimation package: every module a kernel can call into


def user_cache_root() -> Path:
    """The platform's per-user cache folder for the app: ``$XDG_CACHE_HOME/groundstation`` (``~/.cache``),
    ``~/Library/Caches/groundstation`` on macOS, ``%LOCALAPPDATA%\\groundstation\\cache`` on Windows."""
    if sys.platform == "win32":
        return Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local") / "groundstation" / "cache"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "groundstation"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".cache"  # a relative XDG path is invalid
    return base / "groundstation"


def sources_hash() -> str:
    """A hash of every estimation module's bytes, in name order (16 hex digits)."""
    digest = hashlib.sha256()
    for path in sorted(SOURCES.glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def use_user_cache() -> str:
    """Point numba's cache at the user's cache folder (unless ``NUMBA_CACHE_DIR`` says otherwise); returns it."""
    folder = os.environ.get(ENV_VAR) or str(user_cache_root() / "numba" / sources_hash())
    os.environ[ENV_VAR] = folder
    numba = sys.modules.get("numba")
    if numba is not None:  # imported before us: its config has read the environment already
        numba.config.CACHE_DIR = folder
    return folder


class _BeforeNumba:
    """An import hook (``sys.meta_path``) that points numba's cache at the user's folder when numba is
    first imported, then steps aside: it finds no module itself."""

    def find_spec(self, name, path=None, target=None):
        if name == "numba":
            sys.meta_path.remove(self)
            use_user_cache()
        return None


def use_user_cache_for_numba() -> None:
    """``use_user_cache`` now if numba is imported already, else just before it is."""
    if "numba" in sys.modules:
        use_user_cache()
    elif not any(isinstance(finder, _BeforeNumba) for finder in sys.meta_path):
        sys.meta_path.insert(0, _BeforeNumba())


class WarmUp:
    """A process compiling estimators' kernels into numba's cache, in the order named: their per-sample
    kernels first (what a live session waits for), then their batch loops (what a later export or
    replay would compile). ``compiled`` holds the names whose per-sample kernel is in the cache, as the
    process says so; ``generation`` counts them (a cheap "anything new?" for the reader thread)."""

    def __init__(self, names):
        self.names = tuple(names)
        self.compiled: set[str] = set()
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
                    return
                self.compiled.add(name)
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

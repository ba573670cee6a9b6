"""Every log under a folder, each in a process of its own, into one Parquet dataset (``logbook``).

Locally: worker processes (spawned: no fork of a process holding threads), as many as the cores and the
free memory allow (``worker_count``), each given one log at a time. The batch always finishes: a log
whose task raises, whose worker dies (a crash in a C extension, the memory killer) or takes longer than
the per-log time limit (its worker is ended) costs its log only, which gets an error row. A worker that
died is given its log once more, alone, at the end (the memory killer may have picked it for what the
others held); a log past the time limit is not tried again. With ``dask_scheduler`` the same task runs
on a Dask cluster (``distributed``, the existing engine for this; the output folder must be one the
workers can write; the time limit is the cluster's own business there).

The dataset is written to a hidden folder beside ``out`` and moved in place whole when complete, so a
failed or interrupted run leaves no half dataset and a rerun never mixes in an earlier run's logs. An
``out`` that holds anything is replaced only with ``overwrite``, and only when it is such a dataset
(``logs.parquet`` in it): a folder of other files is never removed.
"""

from __future__ import annotations

import collections
import functools
import multiprocessing
import multiprocessing.connection
import os
import secrets
import shutil
import signal
import time
from collections.abc import Callable
from pathlib import Path

from groundstation.errors import UserError
from groundstation.logbook import DEFAULT_LIMIT_S
from groundstation.logbook.summary import LOG_COLUMNS, log_fields, summarise, unify_tables

# A worker's peak memory, for the bound on their number (more than the free memory holds would have the
# memory killer choose among them). Measured (/usr/bin/time, summarise with its report page): 0.28-0.32 GB
# on the largest shared logs (4 MB .tlog, .ulg and .bin), most of it the imports; 1 GB leaves room for
# logs several times as long.
MEMORY_PER_WORKER_BYTES = 2**30


def logs_in(folder: Path, out: Path | None = None) -> list[Path]:
    """The recordings and flight logs under ``folder`` (by suffix, ``formats``), sorted; hidden files and
    folders and the output folder are left out. UserError for a link named as a log that leads nowhere
    (to itself, or to what is gone)."""
    from groundstation import formats

    suffixes = tuple(s for f in formats.FORMATS.values() for s in f.suffixes)
    found = []
    for path in sorted(folder.rglob("*")):
        parts = path.relative_to(folder).parts
        if any(p.startswith(".") for p in parts) or not path.name.lower().endswith(suffixes):
            continue
        try:
            resolved = path.resolve(strict=True)
        except (OSError, RuntimeError):  # RuntimeError: a link to itself (Python 3.11)
            raise UserError(f"{path}: a link that leads nowhere (to itself, or to a file that is gone); "
                            "remove it or make it point to a log") from None
        if out is not None and out.resolve() in resolved.parents:
            continue
        if path.is_file():
            found.append(path)
    return found


def evaluate_folder(folder, out, filters=None, workers: int | None = None, dask_scheduler: str | None = None,
                    progress: Callable[[int, int, Path, list[dict], float], None] | None = None,
                    pages: bool = False, limit_s: float = DEFAULT_LIMIT_S, overwrite: bool = False,
                    task: Callable = summarise) -> list[dict]:
    """Every log's rows (``summary.LOG_COLUMNS``), written as ``out/logs.parquet`` beside ``out/tables``;
    ``progress(done, total, path, rows, seconds)`` after each log; ``pages``: each log's flight report in
    ``out/reports/`` and ``out/index.html`` listing them worst first. ``workers`` processes at most
    (bounded by ``worker_count``), each log ``limit_s`` seconds at most. ``task(path, root, out, filters,
    page)``: what is done on each log (``summary.summarise``; tests put faults in its way)."""
    folder, out = Path(folder), Path(out)
    if not folder.is_dir():
        raise UserError(f"{folder}: not a folder")
    staging = staging_folder(out, folder, overwrite)
    try:
        paths = logs_in(folder, out)
        if not paths:
            raise UserError(f"{folder}: no recordings or flight logs in it")
        results: dict[Path, list[dict]] = {}
        started = time.monotonic()

        def finished(path: Path, rows: list[dict]) -> None:
            results[path] = rows
            if progress is not None:
                progress(len(results), len(paths), path, rows, time.monotonic() - started)

        job = functools.partial(task, page=pages)
        if dask_scheduler:
            _on_dask(job, paths, folder, staging, filters, dask_scheduler, finished)
        else:
            _on_processes(job, paths, folder, staging, filters, worker_count(workers)[0], limit_s, finished)
        if (staging / "tables").is_dir():  # none when no log could be read
            unify_tables(staging / "tables")
        rows = [row for path in paths for row in results[path]]
        write_logs(rows, staging / "logs.parquet")
        if pages:
            from groundstation.logbook.index import write_index  # here: each worker imports this module, not the index's

            write_index(rows, staging / "index.html")
        swap_in(staging, out)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return rows


def staging_folder(out: Path, folder: Path, overwrite: bool) -> Path:
    """A new hidden folder beside ``out`` for the dataset, once ``out`` is known to be replaceable (absent,
    empty, or with ``overwrite`` a dataset of ours, not holding the logs of ``folder``); UserError in one
    line for every path mistake."""
    if os.path.lexists(out) and not out.is_dir():
        raise UserError(f"{out} is a file (or a link to none); --out names the folder the dataset goes to")
    try:
        resolved = out.resolve()
    except RuntimeError:  # Python 3.11's word for a link on the way that leads to itself
        raise UserError(f"cannot write {out}: a link on its way leads to itself") from None
    if resolved == folder.resolve() or resolved in folder.resolve().parents:
        raise UserError(f"{out} holds the logs of {folder}: the dataset goes to a folder of its own, which a rerun "
                        "replaces whole")
    if out.is_dir() and any(out.iterdir()):
        if not overwrite:
            raise UserError(f"{out} exists and is not empty; choose a new folder, or pass --overwrite to replace "
                            "the dataset in it")
        if not (out / "logs.parquet").is_file():
            raise UserError(f"{out} holds files but no dataset (no logs.parquet): --overwrite replaces only a "
                            "dataset this command wrote; choose a new or empty folder")
    staging = out.parent / f".{out.name}.gs-{secrets.token_hex(4)}"
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        if out.is_dir():  # tried, not guessed from permission bits: the dataset is to be written where it was
            (out / staging.name).mkdir()
            (out / staging.name).rmdir()
        staging.mkdir()
    except OSError as error:
        raise UserError(f"cannot write {out}: {error.strerror} ({error.filename})") from None
    return staging


def swap_in(staging: Path, out: Path) -> None:
    """``staging`` becomes ``out``; an earlier ``out`` is removed only once the new one is in place."""
    earlier = out.parent / f".{out.name}.gs-earlier-{secrets.token_hex(4)}"
    try:
        if out.is_dir():
            os.rename(out, earlier)
        try:
            os.rename(staging, out)
        except OSError:
            if earlier.is_dir():
                os.rename(earlier, out)  # the earlier dataset back as it was
            raise
    except OSError as error:
        raise UserError(f"cannot put the dataset in place at {out}: {error.strerror}") from None
    shutil.rmtree(earlier, ignore_errors=True)


def free_memory_bytes() -> int | None:
    """Memory the system can give without swapping (Linux' MemAvailable), else the free pages; None if unknown."""
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def worker_count(requested: int | None) -> tuple[int, str | None]:
    """How many workers at once: ``requested`` (None: as many as possible) bounded by the cores this process
    may use and by the free memory at ``MEMORY_PER_WORKER_BYTES`` each, one at least; and what to tell the
    user when a request was cut down (else None)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    free = free_memory_bytes()
    by_memory = max(1, free // MEMORY_PER_WORKER_BYTES) if free is not None else cores
    count = max(1, min(requested or cores, cores, by_memory))
    if requested is None or count == requested:
        return count, None
    memory = f", {free / 2**30:.1f} GB of memory free at about {MEMORY_PER_WORKER_BYTES / 2**30:g} GB a worker" \
        if free is not None else ""
    return count, f"--workers {requested}: {count} at once ({cores} cores{memory})"


def _on_processes(task, paths, folder, out, filters, workers: int, limit_s: float, finished) -> None:
    died = _pool(task, paths, folder, out, filters, workers, limit_s, finished, last_try=False)
    _pool(task, died, folder, out, filters, 1, limit_s, finished, last_try=True)  # alone: nothing else holds memory


class _Worker:
    """A spawned process that runs the task on each log it is given (``_serve``)."""

    def __init__(self, context, task):
        self.connection, theirs = context.Pipe()
        self.process = context.Process(target=_serve, args=(theirs, task), daemon=True)
        self.process.start()
        theirs.close()  # only the worker holds its end: when it dies, ours reads the end of the file
        self.ready, self.path, self.since = False, None, None

    def give(self, path, job) -> None:
        self.connection.send(job)
        self.path, self.since = path, time.monotonic()

    def end(self) -> None:
        self.process.kill()
        self.process.join()
        self.connection.close()


def _serve(connection, task) -> None:
    """A worker's life: say it is ready, then run ``task`` on each log it is sent until told to stop (None).
    An exception is sent back as its text: the log's error, the worker lives on."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole process group: the batch ends its workers
    connection.send(None)
    while (job := connection.recv()) is not None:
        try:
            connection.send(("rows", task(*job)))
        except Exception as error:  # anything a defect raises: this log's error, not the batch's
            connection.send(("error", f"internal error ({type(error).__name__}: {error})"))


def _pool(task, paths, folder, out, filters, workers: int, limit_s: float, finished, last_try: bool) -> list:
    """Runs ``task`` on every path, ``workers`` at a time; returns the paths whose worker died (each has its
    error row instead when ``last_try``)."""
    pending, died, busy = collections.deque(paths), [], []
    context = multiprocessing.get_context("spawn")
    idle: list[_Worker] = []
    started_one = False  # a worker got as far as its first log: one that dies before is no sign of a broken setup

    def error_row(path, error: str) -> None:
        finished(path, [{**log_fields(Path(path), Path(folder)), "error": error}])

    try:
        while pending or busy:
            while len(idle) < len(pending) and len(idle) + len(busy) < workers:
                idle.append(_Worker(context, task))
            for worker in [w for w in idle if w.ready and pending]:
                path = pending.popleft()
                worker.give(path, (path, folder, out, filters))
                idle.remove(worker)
                busy.append(worker)
            deadlines = [w.since + limit_s for w in busy]
            wait_s = max(0.0, min(deadlines) - time.monotonic()) if deadlines else None
            for connection in multiprocessing.connection.wait([w.connection for w in idle + busy], wait_s):
                worker = next(w for w in idle + busy if w.connection is connection)
                try:
                    said = connection.recv()
                except (EOFError, OSError):  # the worker died
                    worker.end()
                    (idle if worker in idle else busy).remove(worker)
                    if not worker.ready and not started_one:  # none ever started: the next would die the same way
                        raise UserError(f"a worker process could not start ({_exit_said(worker.process.exitcode)})")
                    if worker.path is None:
                        continue
                    if last_try:
                        error_row(worker.path, f"the process reading it died ({_exit_said(worker.process.exitcode)}: "
                                               "a crash, or out of memory)")
                    else:
                        died.append(worker.path)
                    continue
                if said is None:
                    worker.ready = started_one = True
                    continue
                path, (kind, value) = worker.path, said
                busy.remove(worker)
                idle.append(worker)
                worker.path = worker.since = None
                if kind == "rows":
                    finished(path, value)
                else:
                    error_row(path, value)
            for worker in [w for w in busy if time.monotonic() - w.since >= limit_s]:
                busy.remove(worker)
                worker.end()
                error_row(worker.path, f"stopped after {limit_s:g} s, the per-log time limit (--time-limit): "
                                       "its worker was ended")
    finally:
        for worker in idle + busy:
            worker.end()
    return died


def _exit_said(exitcode: int | None) -> str:
    if exitcode is not None and exitcode < 0:
        return f"killed by signal {-exitcode}"
    return f"exit status {exitcode}"


def _on_dask(task, paths, folder, out, filters, scheduler, finished) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError as error:
        raise UserError(f"--dask needs Dask ({error}): pip install \"groundstation[dask]\"") from None
    try:
        client = Client(scheduler, timeout="5s")
    except (OSError, TimeoutError, ValueError) as error:
        raise UserError(f"--dask {scheduler}: cannot reach the scheduler ({error})") from None
    with client:
        futures = {client.submit(task, str(p), str(folder), str(out), filters, pure=False): p for p in paths}
        for future in as_completed(futures):
            path = futures[future]
            try:
                rows = future.result()
            except Exception as error:  # a worker lost with its task: the log's error row
                rows = [{**log_fields(path, folder), "error": f"the Dask task failed ({type(error).__name__}: {error})"}]
            finished(path, rows)


def write_logs(rows: list[dict], path: Path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    from groundstation.export.files import atomic_output

    types = {"string": pa.string(), "double": pa.float64(), "int64": pa.int64()}
    schema = pa.schema([(name, types[kind]) for name, kind in LOG_COLUMNS.items()])
    columns = {name: [row.get(name) for row in rows] for name in LOG_COLUMNS}
    table = pa.Table.from_pydict(columns, schema=schema)
    with atomic_output(path, overwrite=True) as temporary:
        pq.write_table(table, temporary)

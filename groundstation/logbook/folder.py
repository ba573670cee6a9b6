"""Every log under a folder, each in its own process, into one Parquet dataset (``logbook``).

Locally: a pool of spawned processes, one per core, a task per log; a worker that dies (a crash in a
C extension, the memory killer) costs its log only: the log gets an error row and the pool is made
anew for the rest. With ``dask_scheduler`` the same task runs on a Dask cluster (``distributed``,
the existing engine for this; the output folder must be one the workers can write).
"""

from __future__ import annotations

import concurrent.futures
import functools
import multiprocessing
import os
import time
from collections.abc import Callable
from pathlib import Path

from groundstation.errors import UserError
from groundstation.logbook.index import write_index
from groundstation.logbook.summary import LOG_COLUMNS, log_fields, summarise, unify_tables


def logs_in(folder: Path, out: Path | None = None) -> list[Path]:
    """The recordings and flight logs under ``folder`` (by suffix, ``formats``), sorted; hidden files and
    folders and the output folder are left out."""
    from groundstation import formats

    suffixes = tuple(s for f in formats.FORMATS.values() for s in f.suffixes)
    found = []
    for path in sorted(folder.rglob("*")):
        parts = path.relative_to(folder).parts
        if any(p.startswith(".") for p in parts) or (out is not None and out.resolve() in path.resolve().parents):
            continue
        if path.is_file() and path.name.lower().endswith(suffixes):
            found.append(path)
    return found


def evaluate_folder(folder, out, filters=None, workers: int | None = None, dask_scheduler: str | None = None,
                    progress: Callable[[int, int, Path, list[dict], float], None] | None = None,
                    pages: bool = False) -> list[dict]:
    """Every log's rows (``summary.LOG_COLUMNS``), written as ``out/logs.parquet`` beside ``out/tables``;
    ``progress(done, total, path, rows, seconds)`` after each log; ``pages``: each log's flight report in
    ``out/reports/`` and ``out/index.html`` listing them worst first."""
    folder, out = Path(folder), Path(out)
    if not folder.is_dir():
        raise UserError(f"{folder}: not a folder")
    paths = logs_in(folder, out)
    if not paths:
        raise UserError(f"{folder}: no recordings or flight logs in it")
    out.mkdir(parents=True, exist_ok=True)
    run = _on_dask if dask_scheduler else _on_processes
    results: dict[Path, list[dict]] = {}
    started = time.monotonic()

    def finished(path: Path, rows: list[dict]) -> None:
        results[path] = rows
        if progress is not None:
            progress(len(results), len(paths), path, rows, time.monotonic() - started)

    task = functools.partial(summarise, page=pages)
    run(task, paths, folder, out, filters, workers, dask_scheduler, finished)
    if (out / "tables").is_dir():  # none when no log could be read
        unify_tables(out / "tables")
    rows = [row for path in paths for row in results[path]]
    write_logs(rows, out / "logs.parquet")
    if pages:
        write_index(rows, out / "index.html")
    return rows


def _on_processes(task, paths, folder, out, filters, workers, _scheduler, finished) -> None:
    pending = list(paths)
    workers = max(1, workers or os.cpu_count() or 1)
    while pending:
        context = multiprocessing.get_context("spawn")  # no fork of a process holding threads (Qt, pyarrow)
        with concurrent.futures.ProcessPoolExecutor(min(workers, len(pending)), mp_context=context) as pool:
            futures = {pool.submit(task, p, folder, out, filters): p for p in pending}
            broken = False
            for future in concurrent.futures.as_completed(futures):
                path = futures[future]
                try:
                    rows = future.result()
                except concurrent.futures.process.BrokenProcessPool:
                    broken = True
                    continue
                pending.remove(path)
                finished(path, rows)
        if broken:
            # A worker died; the pool does not say on which log, so the first unfinished one runs alone
            # (an error row if it dies again) and a new pool takes the rest.
            _alone(task, pending.pop(0), folder, out, filters, finished)


def _alone(task, path, folder, out, filters, finished) -> None:
    """Runs one log in a process of its own: its rows, or an error row when that process dies too."""
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(1, mp_context=context) as pool:
        try:
            rows = pool.submit(task, path, folder, out, filters).result()
        except concurrent.futures.process.BrokenProcessPool:
            rows = [{**log_fields(Path(path), Path(folder)), "error": "the process reading it died (a crash or out of memory)"}]
    finished(path, rows)


def _on_dask(task, paths, folder, out, filters, _workers, scheduler, finished) -> None:
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

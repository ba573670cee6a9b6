"""Excel export speed and memory: a simulated 100 Hz session (1 hour by default) to .xlsx, and in the
same run bare openpyxl write-only writing the same cells, bare XlsxWriter (``constant_memory``) writing
the same cells, the CSV export and the Parquet export.

    python bench/bench_excel.py [--minutes M] [--filters ahf,hf]
    python bench/bench_excel.py --recording R.gsrec --baseline /work/main [--repeats 3]

The second form is the issue's row as a user meets it: the whole ``groundstation export R --out X.xlsx``
process (CPU s = user + system, peak RSS, from the child's rusage), this checkout's and the baseline
checkout's interleaved run by run, with the default estimators, ``ahf,hf`` and the app's live set; the
minimum and the median of the repeats (the machine is shared: CPU seconds rise with its load).

The session is simulated, recorded and decoded once; each writer then runs in a forked child that
shares it. In the child the kernel's peak-RSS mark is reset at the start (/proc/self/clear_refs, Linux),
so "peak" is the child's high-water mark (the session included) and "writer" is the peak minus the
RSS at the start. "bare openpyxl" appends the same values to the same sheets as plain lists: no number
formats, no header styles, no Session sheet, no chart; "bare XlsxWriter" writes the same rows with
``write_row`` (its row-at-a-time path in ``constant_memory`` mode), skipped when xlsxwriter is absent.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from importlib.util import find_spec
from pathlib import Path

import numpy as np
from openpyxl import Workbook

from groundstation.export.columns import export_columns, select_rows
from groundstation.export.excel import write_workbook
from groundstation.export.excel_columns import attitude_block, chart_block, link_blocks, sensor_blocks
from groundstation.export.excel_stream import CHUNK_ROWS, layout, table_rows
from groundstation.export.tabular import write_csv, write_parquet
from groundstation.recording import RecordingWriter
from groundstation.session_makers.load import load_session
from groundstation.sim.stream import Scenario, SimStream


def simulate(path: Path, minutes: float) -> None:
    stream = SimStream(Scenario(profile="flight", duration_s=60.0 * minutes, seed=1))
    with RecordingWriter(path, {"source": "bench_excel", "port": "simulated"}) as writer:
        t = 0.0
        while t < stream.end_s:
            t = min(t + 60.0, stream.end_s)
            for chunk in stream.advance(t):
                writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)
        for chunk in stream.flush():
            writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)


def tables(data) -> dict:
    """The workbook's data sheets, as ``write_workbook`` builds them."""
    rows = np.arange(len(data))
    window = (data.time_s[0], data.time_s[-1])
    return {"Attitude": [attitude_block(data, rows)], "Sensors": sensor_blocks(data, rows, window, None),
            "Link": link_blocks(data, window), "Chart data": [chart_block(data, rows)]}


def sheet_rows(blocks):
    """The header, then the sheet's rows as lists of plain values (None: empty cell)."""
    columns = layout(blocks)
    yield [c.header if c else None for c in columns]
    n = table_rows(blocks)
    values = np.full((n, len(columns)), np.nan)
    for j, column in enumerate(columns):
        if column is not None:
            values[: len(column.values), j] = column.values
    for start in range(0, n, CHUNK_ROWS):
        part = values[start : start + CHUNK_ROWS]
        yield from np.where(np.isfinite(part), part, None).tolist()  # Excel has no NaN


def bare_openpyxl(data, path: Path) -> None:
    """The same cells through openpyxl's documented write-only path: rows of plain values."""
    workbook = Workbook(write_only=True)
    for title, blocks in tables(data).items():
        sheet = workbook.create_sheet(title)
        for row in sheet_rows(blocks):
            sheet.append(row)
    workbook.save(path)


def bare_xlsxwriter(data, path: Path) -> None:
    """The same cells through XlsxWriter's constant_memory mode, one write_row per row."""
    import xlsxwriter

    workbook = xlsxwriter.Workbook(path, {"constant_memory": True})
    for title, blocks in tables(data).items():
        sheet = workbook.add_worksheet(title)
        for i, row in enumerate(sheet_rows(blocks)):
            sheet.write_row(i, 0, row)
    workbook.close()


def cells(data) -> int:
    return sum(sum(len(c.values) for c in layout(blocks) if c) for blocks in tables(data).values())


def memory_kb(field: str) -> int:
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith(field))


def measure(label: str, write) -> dict:
    """Runs ``write()`` in a forked child; returns its seconds and memory figures."""
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read_end)
        with open("/proc/self/clear_refs", "w") as clear:
            clear.write("5")  # reset the peak-RSS mark to the current RSS
        start_kb = memory_kb("VmRSS")
        started, cpu_started = time.perf_counter(), time.process_time()
        write()
        seconds, cpu_s = time.perf_counter() - started, time.process_time() - cpu_started
        result = {"label": label, "seconds": seconds, "cpu_s": cpu_s, "peak_mb": memory_kb("VmHWM") / 1024,
                  "writer_mb": (memory_kb("VmHWM") - start_kb) / 1024}
        os.write(write_end, json.dumps(result).encode())
        os._exit(0)
    os.close(write_end)
    with os.fdopen(read_end) as pipe:
        text = pipe.read()
    _, status = os.waitpid(pid, 0)
    if status != 0 or not text:
        raise SystemExit(f"{label}: the child failed (status {status})")
    return json.loads(text)


FILTER_SETS = {"default": [], "ahf,hf": ["--filters", "ahf,hf"],
               "live set": ["--filters", "ahf2,vqf,ahf,hf,ecf,hfm,ecfm,mcf,ukf,sssrukf"]}


def export_process(checkout: Path, recording: Path, out: Path, options: list[str]) -> tuple[float, float]:
    """``python -m groundstation export`` run from ``checkout`` (its code first on the path): (CPU s, peak MB)."""
    command = [sys.executable, "-m", "groundstation", "export", str(recording), "--out", str(out), "--overwrite", *options]
    environment = dict(os.environ, PYTHONPATH=os.pathsep.join([str(checkout), os.environ.get("PYTHONPATH", "")]))
    with tempfile.TemporaryFile("w+") as said:  # its progress bar and any error
        child = subprocess.Popen(command, cwd=checkout, env=environment, stdout=subprocess.DEVNULL, stderr=said)
        _, status, usage = os.wait4(child.pid, 0)  # the child's own rusage: Popen.wait would reap it without
        child.returncode = os.waitstatus_to_exitcode(status)
        if child.returncode != 0:
            said.seek(0)
            raise SystemExit(f"{checkout}: {' '.join(command)} failed ({child.returncode}):\n{said.read()[-2000:]}")
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def whole_process(recording: Path, baseline: Path, repeats: int) -> None:
    here = Path(__file__).resolve().parent.parent
    runs = {(name, tree): [] for name in FILTER_SETS for tree in ("this", "baseline")}
    with tempfile.TemporaryDirectory(prefix="bench_excel.") as folder:
        for _ in range(repeats):
            for name, options in FILTER_SETS.items():
                for tree, checkout in (("baseline", baseline), ("this", here)):
                    runs[name, tree].append(export_process(checkout, recording, Path(folder) / f"{tree}.xlsx", options))
    print(f"{recording.name}: whole `groundstation export` process to .xlsx, {repeats} runs each, interleaved\n")
    print("| estimators | checkout | CPU s min | CPU s median | CPU s all | peak RSS (MB) |")
    print("|---|---|---:|---:|---|---:|")
    for (name, tree), figures in runs.items():
        cpu = [c for c, _ in figures]
        print(f"| {name} | {tree if tree == 'this' else baseline} | {min(cpu):.1f} | {statistics.median(cpu):.1f} | "
              f"{', '.join(f'{c:.1f}' for c in cpu)} | {max(m for _, m in figures):.0f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=60.0, help="simulated minutes (default 60)")
    parser.add_argument("--filters", default="ahf,hf", help="host estimators (default ahf,hf)")
    parser.add_argument("--recording", type=Path, help="whole-process runs of the export of this recording")
    parser.add_argument("--baseline", type=Path, help="with --recording: the checkout to compare with")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    if args.recording is not None:
        whole_process(args.recording, args.baseline, args.repeats)
        return
    with tempfile.TemporaryDirectory(prefix="bench_excel.") as folder:
        folder = Path(folder)
        started = time.perf_counter()
        simulate(folder / "session.gsrec", args.minutes)
        data = load_session(folder / "session.gsrec", args.filters.split(","))
        hours = (data.time_s[-1] - data.time_s[0]) / 3600.0
        print(f"session: {len(data)} samples ({hours * 60:.1f} min at 100 Hz), filters {args.filters}, "
              f"simulated and decoded in {time.perf_counter() - started:.0f} s; RSS {memory_kb('VmRSS') / 1024:.0f} MB")
        columns = export_columns(data, select_rows(data.time_s))
        runs = [
            ("xlsx (write_workbook)", "a.xlsx", lambda p: write_workbook(data, p)),
            ("bare openpyxl write-only", "b.xlsx", lambda p: bare_openpyxl(data, p)),
            *([("bare XlsxWriter constant_memory", "e.xlsx", lambda p: bare_xlsxwriter(data, p))] if find_spec("xlsxwriter") else []),
            (f"CSV ({len(columns)} columns)", "c.csv", lambda p: write_csv(columns, p)),
            (f"Parquet ({len(columns)} columns)", "d.parquet", lambda p: write_parquet(columns, p)),
        ]
        results = []
        for label, name, write in runs:
            result = measure(label, lambda: write(folder / name))
            result["file_mb"] = (folder / name).stat().st_size / 1e6
            results.append(result)
        print(f"workbook data cells: {cells(data):,} (bare openpyxl writes the same)\n")
        print("| writer | seconds | CPU s | M cells per CPU s | s per exported hour | peak RSS (MB) | writer's own (MB) | file (MB) |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|")
        for r in results:
            print(f"| {r['label']} | {r['seconds']:.1f} | {r['cpu_s']:.1f} | {cells(data) / r['cpu_s'] / 1e6:.2f} | "
                  f"{r['seconds'] / hours:.1f} | {r['peak_mb']:.0f} | "
                  f"{r['writer_mb']:.0f} | {r['file_mb']:.1f} |")
        print(f"\nxlsx / bare openpyxl: {results[0]['cpu_s'] / results[1]['cpu_s']:.2f}x the CPU time")
        if find_spec("xlsxwriter"):
            print(f"bare XlsxWriter / bare openpyxl: {results[2]['seconds'] / results[1]['seconds']:.2f}x the time")


if __name__ == "__main__":
    main()

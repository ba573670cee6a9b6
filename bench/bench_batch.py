"""The batch path on long recordings: decode speed, session build, estimators, exports, memory.

    python bench/bench_batch.py [--hours H] [--long-hours L] [--repeats R]

A simulated flight (mode raw, 100 Hz, like bench_session.py) of H hours, and one of L hours for
linearity, are written as recordings. Then, each job in a fresh process (peak memory is its own
``ru_maxrss``), medians of R:

1. Decode, frames/s: ``StreamDecoder`` fed the bytes in 4 KiB chunks; the batch decode
   (``firmware_protocol.batch.decode_batch``) of the whole stream; and its framing alone (sync
   search and table CRC of every candidate as array operations: the bare numpy scan).
2. The session: ``batch_replay`` with no estimator (decode + units + clock + tables + link: the
   build), then each of ahf, hf, ecf's ``run`` over the hour's samples, timed apart so the figures
   can be re-measured when the estimators change; the whole ``load_session`` with ahf+hf+ecf; and
   the incremental replay (``replay`` + ``from_pipeline``) it replaces.
3. Exports of that session: CSV (``write_csv``) against a bare pyarrow CSV write of the same table,
   Parquet (``write_parquet``) against a bare ``pyarrow.parquet.write_table``. The xlsx figures are
   bench_excel.py's.
4. The L-hour recording through ``load_session`` with ahf+hf+ecf: time and peak memory against the
   H-hour one (linear: the ratio of the durations).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench_session import make_recording

JOB = r"""
import json, resource, sys, time
kind, path, out = sys.argv[1], sys.argv[2], sys.argv[3]
from groundstation.recording import open_recording
t0 = time.perf_counter()
result = {}
if kind == "stream_decoder":
    from firmware_protocol import StreamDecoder
    data, _, _ = open_recording(path).stream()
    t0 = time.perf_counter()
    decoder = StreamDecoder()
    for i in range(0, len(data), 4096):
        decoder.feed(data[i : i + 4096])
    result["frames"] = decoder.stats.frames
elif kind == "batch_decode":
    from firmware_protocol.batch import decode_batch
    stream = open_recording(path).stream()
    t0 = time.perf_counter()
    result["frames"] = decode_batch(*stream).stats.frames
elif kind == "framing":
    import numpy as np
    from firmware_protocol import SPEC
    from firmware_protocol.batch import _scan, _Tables
    data, ends, _ = open_recording(path).stream()
    t0 = time.perf_counter()
    result["frames"] = len(_scan(np.frombuffer(data, dtype=np.uint8), ends, _Tables(SPEC), SPEC).starts)
elif kind == "build":
    from groundstation.session_makers.batch import batch_replay
    session = batch_replay(open_recording(path), ())
    result["samples"] = len(session.imu)
elif kind == "estimators":
    import numpy as np
    from groundstation.estimation import create
    from groundstation.session_makers.batch import batch_replay
    imu = batch_replay(open_recording(path), ()).imu.to_dict()
    gyr = np.column_stack([imu[f"gyr_{a}_rad_s"] for a in "xyz"])
    acc = np.column_stack([imu[f"acc_{a}_g"] for a in "xyz"])
    dt = np.diff(imu["device_time_us"], prepend=imu["device_time_us"][0] - 10_000) * 1e-6
    t0 = time.perf_counter()
    for name in ("ahf", "hf", "ecf"):
        t = time.perf_counter()
        create(name).run(gyr, acc, dt)
        result[name] = time.perf_counter() - t
    result["samples"] = len(dt)
elif kind in ("load_session", "incremental"):
    from groundstation.session_makers.load import from_pipeline, load_session
    from groundstation.session_makers.replay import replay
    if kind == "load_session":
        data = load_session(path, ("ahf", "hf", "ecf"))
    else:
        recording = open_recording(path)
        data = from_pipeline(recording, replay(recording, ("ahf", "hf", "ecf")))
    result["samples"] = len(data)
    if out != "-":
        import numpy as np
        import pyarrow as pa
        import pyarrow.csv as pacsv
        import pyarrow.parquet as pq
        from groundstation.export.columns import export_columns
        from groundstation.export.tabular import write_csv, write_parquet
        columns = export_columns(data)
        result["session_seconds"] = time.perf_counter() - t0
        for name, write in [("csv", lambda: write_csv(columns, out + ".csv", overwrite=True)),
                            ("bare_csv", lambda: pacsv.write_csv(pa.table(columns), out + ".bare.csv")),
                            ("parquet", lambda: write_parquet(columns, out + ".parquet", overwrite=True)),
                            ("bare_parquet", lambda: pq.write_table(pa.table(columns), out + ".bare.parquet"))]:
            t = time.perf_counter()
            write()
            result[name] = time.perf_counter() - t
        result["rows"], result["columns"] = len(columns["time_s"]), len(columns)
result["seconds"] = time.perf_counter() - t0
result["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(result))
"""


def job(kind: str, recording: Path, out: str = "-") -> dict:
    done = subprocess.run([sys.executable, "-c", JOB, kind, str(recording), out], capture_output=True, text=True,
                          check=True, cwd=Path(__file__).resolve().parent.parent)
    return json.loads(done.stdout)


def medians(kind: str, recording: Path, repeats: int, out: str = "-") -> dict:
    runs = [job(kind, recording, out) for _ in range(repeats)]
    keys = [k for k, v in runs[0].items() if isinstance(v, float)]
    return {**runs[0], **{k: float(np.median([r[k] for r in runs])) for k in keys},
            "peak_mb": max(r["peak_mb"] for r in runs)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=1.0)
    parser.add_argument("--long-hours", type=float, default=4.0, help="0: skip the linearity run")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        hour, long = Path(folder) / "hour.gsrec", Path(folder) / "long.gsrec"
        t0 = time.perf_counter()
        duration_s = make_recording(hour, args.hours)
        print(f"{args.hours:g} h at 100 Hz: {hour.stat().st_size / 1e6:.0f} MB recording, simulated in {time.perf_counter() - t0:.0f} s; "
              f"medians of {args.repeats}, each job in a fresh process")

        print("\n## decode")
        stream = medians("stream_decoder", hour, args.repeats)
        for kind, label in (("stream_decoder", "StreamDecoder, 4 KiB chunks (baseline)"),
                            ("batch_decode", "batch decode_batch, whole stream"),
                            ("framing", "framing alone (numpy sync + CRC scan)")):
            r = stream if kind == "stream_decoder" else medians(kind, hour, args.repeats)
            print(f"{label:<42} {r['seconds']:6.2f} s  {r['frames'] / r['seconds'] / 1e6:5.2f} M frames/s  "
                  f"{stream['seconds'] / r['seconds']:5.1f}x baseline  peak {r['peak_mb']:4.0f} MB")

        print(f"\n## {args.hours:g} h session, ahf + hf + ecf")
        build = medians("build", hour, args.repeats)
        print(f"batch build, no estimator (decode, units, clock, tables, link) {build['seconds']:6.2f} s  "
              f"{duration_s / build['seconds']:6.0f}x real time  peak {build['peak_mb']:4.0f} MB")
        estimators = medians("estimators", hour, args.repeats)
        for name in ("ahf", "hf", "ecf"):
            print(f"  {name}.run over {estimators['samples']} samples {estimators[name]:6.2f} s  "
                  f"{estimators['samples'] / estimators[name] / 1e3:6.0f} k samples/s")
        whole = medians("load_session", hour, args.repeats, str(Path(folder) / "export"))
        print(f"load_session (batch path, ahf+hf+ecf)     {whole['session_seconds']:6.2f} s  "
              f"{duration_s / whole['session_seconds']:6.0f}x real time  peak {whole['peak_mb']:4.0f} MB (exports included)")
        incremental = job("incremental", hour)
        print(f"incremental replay + from_pipeline (1 run) {incremental['seconds']:6.2f} s  "
              f"{duration_s / incremental['seconds']:6.0f}x real time  peak {incremental['peak_mb']:4.0f} MB  "
              f"(batch: {incremental['seconds'] / whole['session_seconds']:.1f}x faster)")

        print(f"\n## exports of that session ({whole['rows']} rows x {whole['columns']} columns)")
        for name, bare in (("csv", "bare_csv"), ("parquet", "bare_parquet")):
            print(f"{name:<8} {whole[name]:6.2f} s  bare pyarrow {whole[bare]:6.2f} s  {whole[name] / whole[bare]:.2f}x bare;  "
                  f"session + {name}: {(whole['session_seconds'] + whole[name]) / (whole['session_seconds'] + whole[bare]):.2f}x "
                  f"(session + bare write)")

        if not args.long_hours:
            return
        print(f"\n## {args.long_hours:g} h against {args.hours:g} h (load_session, ahf+hf+ecf)")
        t0 = time.perf_counter()
        long_s = make_recording(long, args.long_hours)
        print(f"{args.long_hours:g} h recording: {long.stat().st_size / 1e6:.0f} MB, simulated in {time.perf_counter() - t0:.0f} s")
        long_run = job("load_session", long)
        short_run = job("load_session", hour)
        print(f"{args.hours:g} h: {short_run['seconds']:6.2f} s, peak {short_run['peak_mb']:5.0f} MB;  "
              f"{args.long_hours:g} h: {long_run['seconds']:6.2f} s, peak {long_run['peak_mb']:5.0f} MB;  "
              f"ratios {long_run['seconds'] / short_run['seconds']:.2f} (time), {long_run['peak_mb'] / short_run['peak_mb']:.2f} (memory) "
              f"for {long_s / duration_s:g}x the duration")


if __name__ == "__main__":
    main()

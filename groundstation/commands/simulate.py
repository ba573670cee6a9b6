"""``groundstation simulate``: a simulated session as fast as possible, with its truth.

``--out FILE.gsrec`` writes a recording (docs/recording-format.md): the bytes the bridge would have
sent for the same options, stamped with their simulated arrival times, and the truth as sample
columns in the dataset CSV layout, so that replay, export and ``evaluate`` work on it directly.
Any other name writes the raw bytes alone and, beside them, ``STEM.truth.csv.gz`` with the truth
and the sensor values in the dataset CSV layout (see groundstation/sim/truth_file.py).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from groundstation.errors import UserError
from groundstation.sim.options import add_scenario_arguments, scenario_from_args

BLOCK_S = 60.0  # simulated seconds per step: large enough for numpy, small enough for progress


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_scenario_arguments(parser)
    parser.add_argument("--duration", type=float, default=None, metavar="S", help="simulated seconds (default: per scenario, below)")
    parser.add_argument("--out", required=True, metavar="FILE", help="FILE.gsrec: a recording with its truth; other names: raw bytes")
    parser.add_argument("--truth", default=None, metavar="FILE",
                        help="for raw byte output: truth CSV (.csv or .csv.gz) to write (default: STEM.truth.csv.gz beside --out)")


def chunks(stream, started: float):
    """Every chunk of the scenario, block by block, with a progress line after the first second."""
    t = 0.0
    while t < stream.end_s:
        t = min(t + BLOCK_S, stream.end_s)
        yield from stream.advance(t)
        if time.monotonic() - started > 1.0:
            print(f"\rsimulate: {100.0 * t / stream.end_s:5.1f} %", end="", file=sys.stderr, flush=True)
    yield from stream.flush()


def truth_path_for(out: Path) -> Path:
    return out.with_name(out.name.split(".")[0] + ".truth.csv.gz")


def run(args: argparse.Namespace) -> int:
    from groundstation.export.files import atomic_output, atomic_recording
    from groundstation.recording import EXTENSION
    from groundstation.sim.stream import SimStream
    from groundstation.sim.truth_file import TruthTable

    scenario = scenario_from_args(args, args.duration)
    out = Path(args.out)
    truth_path = Path(args.truth) if args.truth else truth_path_for(out)
    fw = scenario.firmware
    table = TruthTable(fw.accel_fs_g, fw.gyro_fs_dps, fw.mounting)
    stream = SimStream(scenario, on_samples=table)
    started = time.monotonic()
    as_recording = out.suffix == EXTENSION
    for path in (out,) if as_recording else (out, truth_path):
        if path.exists():
            raise UserError(f"{path} exists; choose another name")
    if as_recording:
        with atomic_recording(out, {"source": f"simulated '{scenario.profile}' flight, seed {scenario.seed}",
                                    "scenario": vars(args).get("scenario"), "seed": scenario.seed}) as writer:
            for chunk in chunks(stream, started):
                writer.write_chunk(round(chunk.t_s * 1e9), chunk.data)
            writer.write_samples({name: column.to_numpy(dtype=float) for name, column in table.frame().items()})
        truth_path = out
    else:
        with atomic_output(out) as raw_file, atomic_output(truth_path) as truth_file:
            with open(raw_file, "wb") as sink:
                for chunk in chunks(stream, started):
                    sink.write(chunk.data)
            table.write(truth_file)
    elapsed = time.monotonic() - started
    report = stream.link.report
    print(f"\rsimulate: {stream.end_s:g} s of '{scenario.profile}' in {elapsed:.1f} s: {report.bytes_delivered} bytes -> {out}, "
          f"truth -> {truth_path}; link lost {report.lost} of {report.frames_in} frames, damaged "
          f"{report.truncated + report.corrupted}", file=sys.stderr)
    return 0

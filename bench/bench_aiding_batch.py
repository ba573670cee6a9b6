"""The batch path on a recording with every aiding sensor, against the incremental replay run alongside.

    python bench/bench_aiding_batch.py [--minutes M] [--repeats R]

Since the batch path drives the pipeline's own aiding stage (``session_parts.aiding.Aiding``: readings
handed to the IMU samples, compass heading, position) over its columns instead of re-deriving it with
array code, a recording with a magnetometer (50 Hz), a barometer (25 Hz) and GPS (5 Hz) costs the
batch path a Python loop over its samples. This measures what that costs: ``batch_replay`` with ahf
against the incremental ``replay`` (the baseline), medians of R, in this process.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from groundstation.recording import RecordingWriter, open_recording  # noqa: E402
from groundstation.session_makers.batch import batch_replay  # noqa: E402
from groundstation.session_makers.replay import replay  # noqa: E402
from groundstation.sim.firmware import FirmwareSettings  # noqa: E402
from groundstation.sim.stream import Scenario, SimStream  # noqa: E402
from timing import median_seconds  # noqa: E402

SENSORS = dict(mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=5)


def make_recording(path: Path, duration_s: float) -> None:
    stream = SimStream(Scenario(profile="flight", duration_s=duration_s, seed=5, firmware=FirmwareSettings(mode="raw", **SENSORS)))
    with RecordingWriter(path, {"source": "bench", "filters": ["ahf"]}) as writer:
        t = 0.0
        while t < duration_s:
            t += 60.0
            for chunk in stream.advance(min(t, duration_s)):
                writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)
        for chunk in stream.flush():
            writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--minutes", type=float, default=5.0)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "aided.gsrec"
        make_recording(path, args.minutes * 60)
        recording = open_recording(path)
        batch_replay(recording, ("ahf",))  # compile and warm up
        samples = len(replay(recording, ("ahf",)).imu)
        batch = median_seconds(lambda: batch_replay(recording, ("ahf",)), args.repeats)
        incremental = median_seconds(lambda: replay(recording, ("ahf",)), args.repeats)
    print(f"{args.minutes:g} min, {samples} IMU samples, mag 50 Hz, baro 25 Hz, GPS 5 Hz; ahf; medians of {args.repeats}")
    print(f"incremental replay (baseline)  {incremental:6.2f} s   {args.minutes * 60 / incremental:6.0f}x real time   1.00x")
    print(f"batch_replay                   {batch:6.2f} s   {args.minutes * 60 / batch:6.0f}x real time   "
          f"{incremental / batch:.2f}x faster")


if __name__ == "__main__":
    main()

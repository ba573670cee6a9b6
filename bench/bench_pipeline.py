"""Per-sample cost of the session pipeline: IMU only, and with every aiding sensor.

    python bench/bench_pipeline.py [--seconds S] [--repeats N]

Two simulated flights of S seconds (mode raw, 100 Hz IMU; the second also with magnetometer 50 Hz,
barometer 25 Hz and GPS 10 Hz) are made once as link bytes, then fed through a fresh ``Pipeline``
running ``ahf`` N times each. The baseline, measured in the same run on the same bytes, is the
bare ``StreamDecoder`` (what decoding alone costs). Prints medians in µs per IMU sample and the
ratio to the baseline. Times are the process's CPU time (the machine is shared: wall time would count the others' work); read the ratios.
"""

from __future__ import annotations

import argparse
import statistics
import time

from firmware_protocol import StreamDecoder
from groundstation.session_makers.pipeline import Pipeline
from groundstation.sim.firmware import FirmwareSettings
from groundstation.sim.stream import Scenario, SimStream


def link_bytes(seconds: float, aiding: bool) -> list[tuple[int, bytes]]:
    rates = dict(mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=10) if aiding else {}
    stream = SimStream(Scenario("flight", seconds, seed=3, firmware=FirmwareSettings(mode="raw", **rates)))
    chunks = stream.advance(seconds + 1.0) + stream.flush()
    return [(int(c.t_s * 1e9), c.data) for c in chunks]


def timed(make, chunks) -> tuple[float, int]:
    """Seconds to feed every chunk into a fresh consumer, and the IMU samples it completed."""
    consumer = make()
    start = time.process_time()
    samples = sum(consumer(t, data) for t, data in chunks)
    return time.process_time() - start, samples


def pipeline_feed():
    return Pipeline(("ahf",)).feed


def decoder_feed():
    decoder = StreamDecoder()
    return lambda t, data: sum(f.name == "IMU_RAW" for f in decoder.feed(data))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=120.0)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print(f"simulated flights of {args.seconds:g} s, {args.repeats} repeats each, medians")
    for label, aiding in (("IMU only", False), ("IMU + mag 50 Hz + baro 25 Hz + GPS 10 Hz", True)):
        chunks = link_bytes(args.seconds, aiding)
        figures = {}
        for name, make in (("decoder (baseline)", decoder_feed), ("pipeline, ahf", pipeline_feed)):
            runs = [timed(make, chunks) for _ in range(args.repeats)]
            samples = runs[0][1]
            figures[name] = statistics.median(r[0] for r in runs) / samples * 1e6
        base = figures["decoder (baseline)"]
        print(f"{label}: {samples} IMU samples")
        for name, us in figures.items():
            print(f"  {name:20s} {us:7.2f} µs per IMU sample  ({us / base:4.1f}x the decoder)")


if __name__ == "__main__":
    main()

"""Figures for the simulated bridge through a real pty at 100 Hz (printed, not asserted; Linux).

- achieved IMU_RAW rate, per host second and per device second;
- latency from the bridge's write to the decoded frame in a pyserial reader, p50/p99, beside a
  baseline measured in the same run: a bare writer (a 32-byte frame every 10 ms) and a bare pyserial
  reader, no decoder (measured on this machine before the project: p99 under 1 ms);
- CPU % of the bridge process (utime + stime from /proc over wall time).

    python bench/bench_bridge.py [--seconds 20]
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np
import serial

import firmware_protocol as fp

BARE_WRITER = r"""
import os, sys, time, tty
master, slave = os.openpty()
tty.setraw(slave)
print("bare writer on", os.ttyname(slave), flush=True)
next_t = time.monotonic()
while True:
    next_t += 0.01
    time.sleep(max(0.0, next_t - time.monotonic()))
    os.write(master, time.monotonic_ns().to_bytes(8, "little") + bytes(24))
"""


def cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime + stime


def start(command: list[str]) -> tuple[subprocess.Popen, str]:
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    return process, process.stdout.readline().split()[-1]


def stop(process: subprocess.Popen) -> None:
    process.send_signal(signal.SIGTERM)
    try:
        process.wait(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()


def percentiles_ms(latency_ns) -> str:
    p50, p99 = np.percentile(np.asarray(latency_ns) * 1e-6, [50, 99])
    return f"p50 {p50:.3f} ms, p99 {p99:.3f} ms"


def baseline(seconds: float) -> np.ndarray:
    process, path = start([sys.executable, "-c", BARE_WRITER])
    latency, buffer = [], b""
    try:
        with serial.Serial(path, timeout=0.1) as port:
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                buffer += port.read(port.in_waiting or 1)
                now = time.monotonic_ns()
                while len(buffer) >= 32:
                    latency.append(now - int.from_bytes(buffer[:8], "little"))
                    buffer = buffer[32:]
    finally:
        stop(process)
    return np.array(latency[10:])  # skip the first frames, queued before the port was open


def bridge(seconds: float) -> dict:
    log_path = os.path.join(tempfile.mkdtemp(prefix="bench-bridge-"), "timing.log")
    process, path = start([sys.executable, "-m", "groundstation", "bridge-sim", "--scenario", "flight", "--timing-log", log_path])
    decoded = []  # (host ns at decode, t_us) of each IMU_RAW frame
    decoder = fp.StreamDecoder()
    try:
        with serial.Serial(path, timeout=0.1) as port:
            time.sleep(1.5)  # past the board's 1 s boot calibration
            port.reset_input_buffer()
            cpu0, wall0 = cpu_seconds(process.pid), time.monotonic()
            while time.monotonic() - wall0 < seconds:
                frames = decoder.feed(port.read(port.in_waiting or 1))
                now = time.monotonic_ns()
                decoded += [(now, f["t_us"], f.device_time_us) for f in frames if f.name == "IMU_RAW"]
            cpu1, wall1 = cpu_seconds(process.pid), time.monotonic()
    finally:
        stop(process)
    written = {}
    with open(log_path) as f:
        for line in f:
            write_ns, *stamps = map(int, line.split())
            for t_us in stamps:
                written.setdefault(t_us, write_ns)
    decoded = decoded[1:]  # the first may have waited in the buffer we flushed around
    latency = [now - written[t_us] for now, t_us, _ in decoded if t_us in written]
    device_span_s = (decoded[-1][2] - decoded[0][2]) * 1e-6
    return {
        "latency_ns": np.array(latency),
        "rate_host_hz": len(decoded) / (wall1 - wall0),
        "rate_device_hz": (len(decoded) - 1) / device_span_s,
        "cpu_percent": 100.0 * (cpu1 - cpu0) / (wall1 - wall0),
        "frames": len(decoded),
        "decoder": decoder.stats.as_dict(),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    args = parser.parse_args()
    base = baseline(args.seconds)
    result = bridge(args.seconds)
    print(f"{args.seconds:g} s each, {os.cpu_count()} cores, Python {sys.version.split()[0]}")
    print(f"bare writer -> bare pyserial reader:    latency {percentiles_ms(base)}  ({len(base)} frames)")
    print(f"bridge-sim -> pyserial + StreamDecoder: latency {percentiles_ms(result['latency_ns'])}  ({result['frames']} IMU_RAW frames)")
    ratio = np.percentile(result["latency_ns"], 99) / np.percentile(base, 99)
    print(f"  p99 ratio bridge/bare: {ratio:.2f}")
    print(f"  achieved rate: {result['rate_host_hz']:.2f} Hz per host second, {result['rate_device_hz']:.3f} Hz per device second")
    print(f"  bridge process CPU: {result['cpu_percent']:.1f} % of one core")
    print(f"  decoder: frames_lost {result['decoder']['frames_lost']}, crc_errors {result['decoder']['crc_errors']}")


if __name__ == "__main__":
    main()

"""A first start on a machine (issue 34): numba's cache empty, as after an install. ``record`` records and
its session has data from the first second while another process compiles the estimators' kernels, and
Ctrl-C then ends it with the recording closed. Real processes, each with a cache folder of its own
(``NUMBA_CACHE_DIR``); the moments come from the stopwatch (``groundstation.stopwatch``)."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.estimation.estimation_samples import flight_like_samples
from groundstation.estimation import create
from groundstation.estimation.ukf import Ukf
from groundstation.recording import open_recording
from groundstation.session_parts.estimators import _RESTART, _Deferred
from groundstation.stopwatch import UNCOMPILED
from tests.waiting import LIMIT_S, wait_for

ROOT = Path(__file__).resolve().parents[2]
posix_only = pytest.mark.skipif(os.name != "posix", reason="signals and /proc are POSIX")


def first_start_env(tmp_path: Path) -> dict[str, str]:
    """An empty numba cache of its own, the stopwatch on."""
    return {**os.environ, "PYTHONPATH": str(ROOT), "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "GROUNDSTATION_FIRST_FRAME": "1",
            "XDG_CONFIG_HOME": str(tmp_path / "config"), "GROUNDSTATION_RECORDINGS": str(tmp_path / "recordings")}


def compiled_kernels(cache: Path, name: str) -> list[Path]:
    """The cache's index files of the estimation module ``name``'s per-sample kernel (``ukf.ukf_kernel-*.nbi``)."""
    return list(cache.glob(f"**/{name}.{name}_kernel-*.nbi"))


def processes_with(env_value: str) -> list[int]:
    """The processes whose environment holds ``env_value`` (ours and their children)."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and env_value.encode() in (proc / "environ").read_bytes():
                found.append(int(proc.name))
        except OSError:
            continue  # gone meanwhile, or not ours to read
    return found


class Lines:
    """A process's standard output read as it comes (in a thread), to wait on a line."""

    def __init__(self, process: subprocess.Popen):
        import threading

        self.lines: list[str] = []
        self._thread = threading.Thread(target=lambda: self.lines.extend(iter(process.stdout.readline, "")), daemon=True)
        self._thread.start()

    def starting(self, prefix: str) -> str | None:
        return next((line for line in list(self.lines) if line.startswith(prefix)), None)


@posix_only
def test_record_has_data_from_the_first_second_and_ctrl_c_during_compile_closes_the_recording(tmp_path):
    env = first_start_env(tmp_path)
    record = subprocess.Popen([sys.executable, "-m", "groundstation", "record", "--port", "sim:"], env=env, cwd=tmp_path,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        out = Lines(record)
        wait_for(lambda: out.starting(UNCOMPILED) or record.poll() is not None, what="the first data")
        assert record.poll() is None, record.stderr.read()
        uncompiled = out.starting(UNCOMPILED).removeprefix(UNCOMPILED).strip().split(",")
        # The data came while the kernels were compiling: ukf's, the slowest (compiled last), still is.
        assert "ukf" in uncompiled and "ahf2" in uncompiled
        assert not compiled_kernels(tmp_path / "numba", "ukf")
        wait_for(lambda: len(processes_with(str(tmp_path / "numba"))) > 1, what="the compiling process")
        record.send_signal(signal.SIGINT)  # during the compile
        record.wait(timeout=LIMIT_S)
    finally:
        if record.poll() is None:
            record.kill()
    stderr = record.stderr.read()
    assert record.returncode == 0, stderr
    assert "Traceback" not in stderr
    wait_for(lambda: not processes_with(str(tmp_path / "numba")), what="the compiling process gone with record")
    (path,) = (tmp_path / "recordings").glob("*.gsrec")
    recording = open_recording(path)
    assert recording.closed_cleanly and recording.chunk_count > 0 and not recording.damage


def test_a_slow_estimator_waiting_for_its_kernel_catches_up_as_the_bank_would_have_run_it():
    """ukf is not run interpreted (``EstimatorBank``): its samples, a restart and a settings change wait
    (``_Deferred``), then run through the compiled kernel once it is there: the same estimate, bit for bit,
    as the bank gives an estimator compiled from the start (step; restart from its last q; new settings
    from its last q)."""
    gyr, acc, dt = flight_like_samples(400, 5)
    reference, waiting = create("ukf"), _Deferred(Ukf(dtype=np.float64))  # as a first start makes it
    changed = {"gyro_noise_rad_s": 0.02}
    q = None
    for k in range(400):
        if k == 150:
            reference.restart(q0=q)
            waiting.missed_event(_RESTART)
        if k == 300:
            reference = create("ukf", changed)
            reference.reset(q0=q)
            waiting.missed_event(Ukf(create("ukf", changed).settings, dtype=np.float64))
        q, _ = reference.step(gyr[k].tolist(), acc[k].tolist(), float(dt[k]), None, None)
        assert all(math.isnan(v) for v in waiting.missed(gyr[k].tolist(), acc[k].tolist(), float(dt[k]), None, None))
    estimator, q_caught = waiting.caught_up()
    assert not estimator.interpreted and estimator.settings.gyro_noise_rad_s == 0.02
    assert q_caught == q
    assert estimator.step([0.1, 0.0, 0.0], [0.0, 0.0, -1.0], 0.01) == reference.step([0.1, 0.0, 0.0], [0.0, 0.0, -1.0], 0.01)


def test_export_on_a_first_start_says_it_compiles_before_it_does(tmp_path):
    """``export`` after an install compiles its estimators in the process, seconds each: it says so in one line
    first, so that nobody takes the wait for a hang (the process is stopped once it said it)."""
    sample = ROOT / "recordings" / "samples" / "flight-both-lossy.gsrec"  # its live session ran AHF only
    export = subprocess.Popen([sys.executable, "-m", "groundstation", "export", str(sample), "--out", str(tmp_path / "out.csv")],
                              env=first_start_env(tmp_path), cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        out = Lines(export)
        wait_for(lambda: out.starting("compiling") or export.poll() is not None, what="the line about compiling")
        assert out.starting("compiling 1 estimator for this machine, once"), out.lines
        assert not compiled_kernels(tmp_path / "numba", "ahf")  # said before it compiled
    finally:
        export.kill()
        export.wait()

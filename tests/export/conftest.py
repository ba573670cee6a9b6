"""Small sessions for the export tests: a simulated link recording (every sheet has rows) and a
slice of a BROAD trial (a session with truth)."""

import fcntl
import hashlib
import json
import os
import shutil
import subprocess
from pathlib import Path

import pandas as pd
import pytest

from groundstation.recording import RecordingWriter
from groundstation.session_makers.load import load_session
from groundstation.sim.firmware import FirmwareSettings
from groundstation.sim.link import LinkSettings
from groundstation.sim.stream import Scenario, SimStream

DATASETS = Path(__file__).resolve().parents[2].parent / "shared" / "datasets"
TRIAL = DATASETS / "broad" / "02_undisturbed_slow_rotation_B.csv.gz"
START_UTC = "2024-05-01T12:00:00.000Z"
CHANGE_AT_S = 10.0  # hf.beta changes to 0.3 here


def simulated_recording(path: Path, duration_s: float = 20.0, mode: str = "both") -> Path:
    """A lossy, noisy hover with magnetometer, barometer and GPS, and one settings change."""
    scenario = Scenario(
        profile="hover", duration_s=duration_s, seed=4,
        firmware=FirmwareSettings(mode=mode, mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=5),
        link=LinkSettings(loss=0.01, ber=1e-5),
    )
    stream = SimStream(scenario)
    metadata = {"start_utc": START_UTC, "source": "simulated bridge", "port": "/dev/ttySIM", "filters": ["ahf", "hf"]}
    with RecordingWriter(path, metadata) as writer:
        t = 0.0
        while t < stream.end_s:
            t = min(t + 1.0, stream.end_s)
            for chunk in stream.advance(t):
                writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)
            if t == CHANGE_AT_S:  # as LiveSession.change_settings records it
                event = {"t_host_ns": int(t * 1e9), "kind": "settings", "name": "hf", "settings": {"beta": 0.3}}
                writer.write_event(event["t_host_ns"], event)
        for chunk in stream.flush():
            writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)
    return path


@pytest.fixture(scope="session")
def sim_recording(tmp_path_factory) -> Path:
    return simulated_recording(tmp_path_factory.mktemp("sim") / "hover.gsrec")


@pytest.fixture(scope="session")
def sim_session(sim_recording):
    return load_session(sim_recording, exact=True)  # as every export loads it (``run_export``)


@pytest.fixture(scope="session")
def trial_session(tmp_path_factory):
    """20 s of a real trial from the start of its motion, with truth."""
    if not TRIAL.exists():
        pytest.skip(f"dataset not found at {TRIAL}")
    path = tmp_path_factory.mktemp("trial") / "trial.csv"
    frame = pd.read_csv(TRIAL)
    start = frame.time_s[frame.moving == 1].min() - 5
    frame[(frame.time_s >= start) & (frame.time_s < start + 20)].to_csv(path, index=False)
    return load_session(path, ["ahf", "hf"], exact=True)


JS_READERS = Path(__file__).resolve().parents[1] / "js"


@pytest.fixture(scope="session")
def read_mcap_js(tmp_path_factory):
    """``read(path) -> dict``: an MCAP file as Foxglove's ``@mcap/core`` reads it and Lichtblick parses its
    channels (tests/js/read_mcap.mjs). The packages of tests/js/package-lock.json are installed once
    (``npm ci``) into a cache outside the work tree, kept between runs while the lock file is unchanged."""
    node, npm = shutil.which("node"), shutil.which("npm")
    if node is None or npm is None:
        pytest.skip("node and npm are needed to read MCAP with @mcap/core (apt-get install nodejs npm)")
    lock = (JS_READERS / "package-lock.json").read_bytes()
    home = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    folder = home / "groundstation-tests" / f"js-{hashlib.sha256(lock).hexdigest()[:16]}"
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / ".lock", "w") as lock_file:  # one installer at a time (pytest-xdist's workers)
        fcntl.flock(lock_file, fcntl.LOCK_EX)
        for source in JS_READERS.iterdir():
            target = folder / source.name
            if source.is_file() and (not target.exists() or target.read_bytes() != source.read_bytes()):
                shutil.copyfile(source, target)
        if not (folder / "node_modules" / ".package-lock.json").exists():
            done = subprocess.run([npm, "ci", "--ignore-scripts", "--no-audit", "--no-fund"], cwd=folder,
                                  capture_output=True, text=True, timeout=600)
            assert done.returncode == 0, f"npm ci failed: {done.stderr[-2000:]}"

    def read(path) -> dict:
        done = subprocess.run([node, str(folder / "read_mcap.mjs"), str(path)], capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        return json.loads(done.stdout)

    return read


@pytest.fixture(scope="session")
def exported_log(tmp_path_factory):
    """``export(name) -> (session, mcap path)``: a shared flight log loaded (with ``ahf``) and written to
    MCAP once per test process, for the tests that read the same export in different ways."""
    from groundstation.export.mcap_file import write_mcap

    done = {}

    def export(name: str):
        if name not in done:
            log = DATASETS / "flightlogs" / name
            if not log.exists():
                pytest.skip(f"{log} not found")
            session = load_session(log, ["ahf"], exact=True)
            path = tmp_path_factory.mktemp("exported") / f"{log.stem}.mcap"
            write_mcap(session, path)
            done[name] = session, path
        return done[name]

    return export

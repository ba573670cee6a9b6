"""A computed session played back (``session.playback``): the clock runs at its speed, stops at the end
and on pause; the tables show exactly the computed rows up to the clock, read as a ``Table`` is;
the link figures at the end are the decoder's totals; ``groundstation replay`` computes any file."""

from pathlib import Path

import numpy as np
import pytest

from groundstation.recording import open_recording
from groundstation.session_makers.load import load_session
from groundstation.session_makers.replay import replay
from groundstation.session.playback import Playback, RevealedTable, RevealSession, check_speed
from groundstation.session_parts.table import Table
from tests.cli_in_process import run_in_process

SAMPLES = Path(__file__).resolve().parents[2] / "recordings" / "samples"
LOSSY = SAMPLES / "flight-both-lossy.gsrec"  # losses, CRC failures, both raw and estimated frames
FLIGHTLOGS = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "flightlogs"


def test_the_clock_runs_at_its_speed_pauses_and_stops_at_the_end():
    wall = [100.0]
    clock = Playback(Path("x.gsrec"), duration_s=10.0, speed=2.0, clock=lambda: wall[0])

    def at(now_s: float) -> float:
        wall[0] = now_s
        return clock.advance()

    assert at(100.0) == 0.0  # the first call anchors it
    assert at(101.5) == 3.0  # 1.5 s of wall clock at 2x
    wall[0] = 101.75
    clock.pause(True)  # where it is when paused
    assert at(200.0) == 3.5
    clock.pause(False)  # at 200 s
    assert at(200.5) == 4.5
    clock.speed = 0.25
    assert at(202.5) == 5.0
    clock.move_to(2.0)
    assert at(206.5) == 3.0
    assert at(400.0) == 10.0 and clock.ended  # it stops at the end
    clock.move_to(-5.0)
    assert clock.position_s == 0.0 and not clock.ended
    with pytest.raises(ValueError, match="between 0.25x and 64x"):
        clock.speed = 100.0
    with pytest.raises(ValueError):
        check_speed(0.1)


@pytest.mark.parametrize("layout", ["separate columns", "a Table's to_dict (views of one array: rows are sliced)"])
def test_a_revealed_table_reads_as_the_table_of_the_same_rows(layout):
    rows = np.column_stack([np.arange(10) * 0.1, np.arange(10) ** 2, -np.arange(10)]).astype(float)
    table = Table(("time_s", "a", "b"))
    if layout == "separate columns":
        revealed = RevealedTable({"time_s": rows[:, 0].copy(), "a": rows[:, 1].copy(), "b": rows[:, 2].copy()})
    else:
        whole = Table(("time_s", "a", "b"))
        whole.extend(rows)
        revealed = RevealedTable(whole.to_dict())
    revealed.reveal(0.45)
    table.extend(rows[:5])  # what a live table holds at 0.45 s
    assert len(revealed) == len(table) == 5
    np.testing.assert_array_equal(revealed.array(), table.array())
    np.testing.assert_array_equal(revealed.tail(2), table.tail(2))
    np.testing.assert_array_equal(revealed.tail(99), table.tail(99))
    np.testing.assert_array_equal(revealed.column("a"), table.column("a"))
    assert revealed.to_dict().keys() == table.to_dict().keys()
    revealed.reveal(0.1)  # back: fewer rows
    assert len(revealed) == 2 and revealed.tail(1)[0, 0] == 0.1


def test_a_recording_played_to_the_end_shows_every_row_and_the_decoders_totals():
    data = load_session(LOSSY)
    session = RevealSession(data, LOSSY, paused=True)
    assert len(session.view.imu) == int((data.time_s <= 0.0).sum())
    session.seek(data.time_s[-1] / 2)
    half = session.view.tables["onboard"].to_dict()
    rows = data.tables["onboard"]["time_s"] <= data.time_s[-1] / 2
    for name, values in data.tables["onboard"].items():
        np.testing.assert_array_equal(half[name], values[rows], err_msg=name)
    assert 0 < session.view.counters()["frames_lost"] < data.link.counters["frames_lost"]  # the lost so far
    assert session.seek(session.source.duration_s) is False and not session.running
    for name, table in data.tables.items():
        assert len(session.view.tables[name]) == len(table["time_s"]), name
    counters = session.view.counters()
    assert all(counters[k] == data.link.counters[k] for k in ("frames", "frames_lost", "crc_errors"))
    live = replay(open_recording(LOSSY)).link.clock()  # the live path's latency over the same last samples
    shown = session.view.link.clock()
    for figure in ("latency_p50_ms", "latency_p99_ms"):
        assert shown[figure] == pytest.approx(live[figure], abs=1e-3), figure  # µs: host_time_s is a float
    assert session.seek(1.0) is True  # back in time: the views start over
    session.step()
    assert session.source.position_s == data.time_s[int((data.time_s <= 1.0).sum())]


@pytest.fixture
def gs(capsys):
    return lambda *args: run_in_process(capsys, *args)


def test_replay_command_computes_a_recording_and_plays_it_at_a_pace(gs):
    data = load_session(LOSSY)
    c = data.link.counters
    totals = (f"{len(data)} IMU samples at {data.imu_rate_hz():.1f} Hz over {data.duration_s():.1f} s, {c['frames']} frames, "
              f"{c['frames_lost']} lost ({data.link_loss_pct():.1f} %), {c['crc_errors']} CRC errors, {c['bytes_skipped']} bytes skipped")
    done = gs("replay", LOSSY)
    assert done.returncode == 0 and done.stdout.splitlines() == [totals], done.stderr
    paced = gs("replay", LOSSY, "--speed", "64")  # about half a second of playback
    lines = paced.stdout.splitlines()
    assert paced.returncode == 0 and lines[-1] == totals and lines[0].startswith("t ") and "frames/s" in lines[0]
    bad = gs("replay", LOSSY, "--speed", "100")
    assert bad.returncode == 2 and "between 0.25x and 64x" in bad.stderr


@pytest.mark.parametrize("name", ["px4_fmuv5_quad_hop.ulg", "arduplane_omnibusf4_ground_pilot_0004.bin"])
def test_replay_command_reads_flight_logs(name, gs):
    path = FLIGHTLOGS / name
    if not path.exists():
        pytest.skip(f"{path} is absent (the shared flight logs)")
    data = load_session(path)
    done = gs("replay", path, "--speed", "64")
    assert done.returncode == 0, done.stderr
    last = done.stdout.splitlines()[-1]
    samples = f"{len(data)} IMU samples at {data.imu_rate_hz():.1f} Hz" if data.sample_table == "imu" else f"{len(data)} onboard attitude samples, no IMU"
    assert last == f"{samples} over {data.duration_s():.1f} s"


def test_a_flight_logs_progress_moves_through_its_estimators():
    """The app's progress bar while a log is computed: the reading, then one step per estimator, to the end."""
    path = FLIGHTLOGS / "px4_fmuv5_quad_hop.ulg"  # its reader reports nothing itself
    if not path.exists():
        pytest.skip(f"{path} is absent (the shared flight logs)")
    reports = []
    filters = ("ahf", "hf", "ecf", "cf1")
    load_session(path, filters, progress=lambda done, total: reports.append(done / total))
    assert reports == sorted(reports) and reports[-1] == 1.0
    assert len([r for r in reports if r > 0.3]) == len(filters)  # one report after each estimator's run

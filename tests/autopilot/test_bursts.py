"""ArduPilot's batch sampler (ISBH/ISBD) on the shared CubeOrange log: bursts kept as bursts (issue 31).

The log holds 1,024-sample bursts at ~1975 Hz, gyro and accel in turn, with gaps between them: the tables keep
each sample's batch and its batch's own rate (checked against pymavlink's DFReader read here), the spectra
average over the bursts (checked against scipy's Welch per burst), ``--imu fast`` leaves the estimators on the
logged IMU and says why, and the what-if filters the bursts only, its Bode view and attenuation checked
against scipy. The log is read once for the module."""

import json
from pathlib import Path

import numpy as np
import pytest
from pymavlink import DFReader
from scipy.signal import freqz, lfilter, lfilter_zi, welch

from groundstation.analysis.vibration import LOBE_BINS, VibrationError, vibration_summary
from groundstation.analysis.whatif import LAG_AT_HZ, what_if
from groundstation.autopilot.agreement import onboard_agreement
from groundstation.autopilot.logtables import BATCH, fast_name
from groundstation.session_makers.flight_log_session import log_session, read_log

LOG = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "flightlogs" / "arducopter_cubeorange_2023-07-06_10-12-18.bin"
pytestmark = pytest.mark.skipif(not LOG.exists(), reason="the shared flight logs are not here")
ISB_KIND = {0: "accel", 1: "gyro"}
FILTERS = ["ahf2", "vqf"]
NOTCH_HZ, NOTCH_BW_HZ = 54.2, 27.1  # what `vibration` suggests on this log


@pytest.fixture(scope="module")
def batches():
    """pymavlink's own reading: kind -> [(N, sample times µs, (1024, 3) values in SI units)] per ISBH batch of IMU 0."""
    reader = DFReader.DFReader_binary(str(LOG), zero_time_base=False)
    headers, records = {}, {}
    while (m := reader.recv_match(type=["ISBH", "ISBD"])) is not None:
        if m.get_type() == "ISBH":
            headers[m.N] = m
        elif m.N in headers:
            records.setdefault(m.N, []).append(m)
    out = {"gyro": [], "accel": []}
    for n, h in headers.items():
        if h.instance != 0 or n not in records:
            continue
        values = np.full((h.smp_cnt, 3), np.nan)
        for r in records[n]:
            k = r.seqno * 32 + np.arange(32)
            keep = k < h.smp_cnt
            values[k[keep]] = np.column_stack([np.asarray(r.x), np.asarray(r.y), np.asarray(r.z)])[keep] / h.mul
        logged = np.isfinite(values).all(axis=1)  # the log's last batch was cut short
        out[ISB_KIND[h.type]].append((n, (h.SampleUS + np.arange(h.smp_cnt) * 1e6 / h.smp_rate)[logged], values[logged]))
    return out


@pytest.fixture(scope="module")
def log():
    return read_log(LOG)


@pytest.fixture(scope="module")
def regular(log):
    return log_session(log, FILTERS, {})


@pytest.fixture(scope="module")
def fast(log):
    return log_session(log, FILTERS, {}, imu="fast")


@pytest.mark.parametrize("kind", ["gyro", "accel"])
def test_the_full_rate_tables_keep_each_batch_at_its_own_rate_as_pymavlink_reads_them(log, batches, kind):
    table = log.tables[fast_name(kind, 0)]
    expected = sorted(batches[kind], key=lambda b: b[1][0])
    assert len(expected) > 70
    np.testing.assert_allclose(table.time_us, np.concatenate([t for _, t, _ in expected]), rtol=0, atol=1e-3)
    np.testing.assert_array_equal(table.columns[BATCH], np.concatenate([np.full(len(t), n) for n, t, _ in expected]))
    np.testing.assert_allclose(table.stack(tuple(f"{'gyr' if kind == 'gyro' else 'acc'}_{a}" for a in "xyz")),
                               np.concatenate([v for _, _, v in expected]), rtol=1e-12)


def test_fast_on_bursts_keeps_the_estimators_on_the_logged_imu_and_says_why(regular, fast):
    ours, logged = onboard_agreement(fast), onboard_agreement(regular)
    for name in FILTERS:
        for angle in ("pitch_rms_deg", "roll_rms_deg"):
            assert ours[name][angle] <= logged[name][angle] + 1e-9, (name, angle, ours[name][angle], logged[name][angle])
    said = [w for w in fast.warnings if "bursts" in w]
    assert len(said) == 1 and "logged IMU" in said[0] and "\n" not in said[0]
    assert not any("bursts" in w for w in regular.warnings)
    assert "bursts" in fast.events[0]["message"] and fast.events[0]["kind"] == "warning"  # the app's Events tab


def test_the_spectra_average_welch_over_the_bursts(regular, batches):
    summary = vibration_summary(regular)
    for sensor in ("gyro", "accel"):
        sp = summary.spectra[sensor]
        unit = np.degrees(1.0) if sensor == "gyro" else 1.0
        per_burst = [welch(v * unit, fs=sp.rate_hz, window="hann", nperseg=sp.nperseg, noverlap=sp.nperseg // 2,
                           detrend="constant", axis=0)[1] for _, _, v in batches[sensor] if len(v) >= sp.nperseg]
        assert sp.segments == len(per_burst)
        expected = np.mean(per_burst, axis=0)
        for i, axis in enumerate("xyz"):
            np.testing.assert_allclose(sp.psd[axis], expected[:, i], rtol=1e-6, atol=1e-12 * expected[:, i].max())


@pytest.fixture(scope="module")
def change(regular):
    return what_if(regular, "notch", NOTCH_HZ, NOTCH_BW_HZ)


def test_the_what_if_filters_only_data_sampled_above_twice_its_frequency(regular, change):
    assert set(change.spectra) == {"gyro", "accel"}
    for filtered in change.spectra.values():
        assert filtered.table.endswith("_fast_0") and filtered.rate_hz > 2 * NOTCH_HZ and not filtered.continuous
    assert "('gyro_fast_0' at 1975 Hz, 77 bursts)" in "\n".join(change.lines())
    # the 25 Hz logged IMU carries no 54 Hz filter: no attitude difference, and the reason
    assert change.attitude is None and "bursts" in change.attitude_note and "25 Hz" in change.attitude_note
    with pytest.raises(VibrationError, match="faster than"):
        what_if(regular, "notch", 0.6 * change.spectra["gyro"].rate_hz)  # above every table's Nyquist


def test_the_bode_view_is_scipys_freqz_of_the_same_coefficients(change):
    gyro = change.spectra["gyro"]
    assert change.bode_rate_hz == gyro.rate_hz
    _, h = freqz(gyro.b, gyro.a, worN=change.bode_hz, fs=change.bode_rate_hz)
    ours = 10 ** (change.magnitude_db / 20) * np.exp(1j * np.radians(change.phase_deg))
    np.testing.assert_allclose(ours, h, rtol=0, atol=1e-9)
    lags = change.phase_lag_deg
    assert sorted(lags) == list(LAG_AT_HZ)
    for f, lag in lags.items():
        assert lag == pytest.approx(-np.degrees(np.angle(h[change.bode_hz == f][0])), abs=1e-9)
        assert 0 < lag < 90  # a notch above them delays them


def test_the_attenuation_at_the_peak_is_scipys_filtering_of_the_bursts(change, batches):
    for sensor in ("gyro", "accel"):
        filtered = change.spectra[sensor]
        unit = np.degrees(1.0) if sensor == "gyro" else 1.0
        nperseg = filtered.before.nperseg
        before, after = [], []
        for _, _, v in batches[sensor]:
            if len(v) < nperseg:  # the cut last burst: no whole segment in it
                continue
            x = v * unit
            y = np.column_stack([lfilter(filtered.b, filtered.a, x[:, j], zi=lfilter_zi(filtered.b, filtered.a) * x[0, j])[0]
                                 for j in range(3)])
            for store, data in ((before, x), (after, y)):
                f, p = welch(data, fs=filtered.rate_hz, window="hann", nperseg=nperseg, detrend="constant", axis=0)
                store.append(p.sum(axis=1))
        k = int(np.argmin(np.abs(f - filtered.peak_hz)))
        lobe = slice(k - LOBE_BINS, k + LOBE_BINS + 1)
        expected_db = 10 * np.log10(np.mean(after, axis=0)[lobe].sum() / np.mean(before, axis=0)[lobe].sum())
        assert filtered.attenuation_db == pytest.approx(expected_db, abs=1e-6)
        assert filtered.attenuation_db < -3.0 and filtered.level_after < filtered.level_before
        assert abs(filtered.peak_hz - NOTCH_HZ) < NOTCH_BW_HZ  # in the notch's stop band


def test_vibration_imu_fast_what_if_json_carries_the_same(fast, monkeypatch, capsys):
    from groundstation import cli
    from groundstation.session_makers import load

    asked = []
    monkeypatch.setattr(load, "load_session", lambda path, progress=None, imu="regular": asked.append(imu) or fast)
    assert cli.main(["vibration", str(LOG), "--imu", "fast", "--what-if", "notch", "--json"]) == 0
    out, err = capsys.readouterr()
    assert asked == ["fast"] and "bursts" in err
    change = json.loads(out)["what_if"]
    assert change["frequency_hz"] == NOTCH_HZ and change["spectra"]["gyro"]["rate_hz"] > 2 * NOTCH_HZ
    assert change["spectra"]["gyro"]["attenuation_db"] < -3.0 and len(change["spectra"]["gyro"]["psd_after"]) > 500
    assert set(change["phase_lag_deg"]) == {"10", "20", "30"} and len(change["bode"]["phase_deg"]) > 100
    assert change["attitude"] is None and "bursts" in change["attitude_note"]
    assert cli.main(["vibration", str(LOG), "--imu", "fast", "--what-if", "lowpass", "--what-if-hz", "2000"]) == 2
    assert "faster than 4000 Hz" in capsys.readouterr().err

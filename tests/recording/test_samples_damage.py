"""One flipped bit in an imported dataset recording costs one small block of rows, not the trial;
recordings written with the former 4 MiB blocks still open whole."""

import numpy as np
import pytest

from groundstation.recording import RecordingWriter, open_recording, samples


def trial_columns(n_rows: int = 60_000) -> dict[str, np.ndarray]:
    """A dataset-shaped trial: 13 float columns, ~6 MB of values (the size of a BROAD trial)."""
    rng = np.random.default_rng(7)
    columns = {"time_s": np.arange(n_rows) / 286.0}
    for name in ("gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s", "acc_x_m_s2", "acc_y_m_s2", "acc_z_m_s2",
                 "mag_x_uT", "mag_y_uT", "mag_z_uT", "true_qw", "true_qx", "true_qy"):
        columns[name] = rng.normal(size=n_rows)
    return columns


def test_one_flipped_bit_loses_one_block_of_rows(tmp_path):
    columns = trial_columns()
    path = tmp_path / "trial.gsrec"
    with RecordingWriter(path, {"source": "imported"}) as writer:
        writer.write_samples(columns)
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x10  # one bit, in the middle of the trial
    path.write_bytes(bytes(data))

    recording = open_recording(path)
    kept = recording.samples["time_s"]
    assert len(recording.damage) == 1 and "failed its CRC" in recording.damage[0]
    lost = len(columns["time_s"]) - len(kept)
    assert 0 < lost < 0.02 * len(columns["time_s"])  # one block: 630 rows here, 1 % (was 40,329 rows, 67 %)
    # what is kept is bit for bit what was written, on the same rows
    rows = np.searchsorted(columns["time_s"], kept)
    for name, values in columns.items():
        np.testing.assert_array_equal(recording.samples[name], values[rows])


def test_recordings_with_the_former_4_mib_blocks_still_open(tmp_path, monkeypatch):
    columns = trial_columns()
    monkeypatch.setattr(samples, "BLOCK_BYTES", 4 * 1024 * 1024)  # as the earlier versions wrote them
    path = tmp_path / "old.gsrec"
    with RecordingWriter(path, {"source": "imported"}) as writer:
        writer.write_samples(columns)
    recording = open_recording(path)
    assert recording.record_counts["sample_blocks"] == 2 and recording.damage == []
    for name, values in columns.items():
        np.testing.assert_array_equal(recording.samples[name], values)


@pytest.mark.parametrize("n_columns", [1, 13, 400])
def test_blocks_stay_small_whatever_the_number_of_columns(n_columns):
    columns = samples.as_float64_columns({f"c{i}": np.arange(10_000.0) for i in range(n_columns)})
    payloads = samples.encode_blocks(columns)
    assert all(len(p) <= samples.BLOCK_BYTES + 16 * 1024 for p in payloads[:-1])  # values + the JSON header
    joined = [samples.decode_block(memoryview(p)) for p in payloads]
    np.testing.assert_array_equal(np.concatenate([b["c0"] for b in joined]), np.arange(10_000.0))

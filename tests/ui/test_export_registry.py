"""A new export format is one writer and one registry line: registered here (and removed again after the
test), it appears in the CLI's help and the app's export dialog, and the dialog's job writes it, with no
other edit (a format added to one of two lists once made the dialog raise KeyError)."""

import json

import pandas as pd
import pytest

from groundstation.cli import main
from groundstation.export import request
from groundstation.export.columns import export_columns, select_rows
from groundstation.export.files import atomic_output
from groundstation.session_makers.load import load_session
from groundstation.ui.export_dialog import ExportDialog

from tests.waiting import LIMIT_MS


def export_jsonl(data, export, writing, cancel):
    """JSON Lines, one object a row: a format of one function."""
    rows = select_rows(data.time_s, export.t_from, export.t_to, export.rate_hz)
    columns = export_columns(data, rows)
    with atomic_output(export.out, export.overwrite) as temporary, open(temporary, "w", encoding="utf-8") as out:
        for i in range(len(rows)):
            out.write(json.dumps({name: float(values[i]) for name, values in columns.items()}) + "\n")
    return f"{len(rows)} lines", []


JSONL = request.ExportFormat(".jsonl", "JSON Lines", export_jsonl, decode_share=0.8)


@pytest.fixture
def registered():
    request.register(JSONL)
    yield
    del request.FORMATS[JSONL.suffix]


def test_a_registered_export_format_reaches_the_cli_help_the_dialog_and_its_job(registered, qtbot, recording,
                                                                                tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["export", "--help"])
    assert "OUT.jsonl (JSON Lines)" in " ".join(capsys.readouterr().out.split())

    dialog = ExportDialog(load_session, recording, 30.0)
    qtbot.addWidget(dialog)
    index = dialog.format_box.findData(".jsonl")
    assert dialog.format_box.itemText(index) == "JSON Lines (.jsonl)"
    dialog.format_box.setCurrentIndex(index)
    out = tmp_path / "flight.jsonl"
    dialog.path_edit.setText(str(out))
    dialog.rate.setValue(10)
    dialog.export_button.click()
    qtbot.waitUntil(lambda: dialog.job.done and not dialog.timer.isActive(), timeout=LIMIT_MS)
    assert dialog.status.text().startswith(f"wrote {out}: ") and dialog.progress.value() == 1000

    # The same rows as the CSV writer's at the same rate (an independent writer: pyarrow's).
    lines = pd.read_json(out, lines=True)
    assert main(["export", str(recording), "--out", str(tmp_path / "flight.csv"), "--rate", "10"]) == 0
    table = pd.read_csv(tmp_path / "flight.csv")
    assert len(lines) == len(table) > 250
    pd.testing.assert_series_equal(lines["time_s"], table["time_s"], check_exact=False, rtol=1e-12)

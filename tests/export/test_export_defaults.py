"""What an export holds and where it goes when the user leaves the defaults (issue 24, defect 9): the
estimators the data can run, the same from the app and the CLI; readable Session labels; a chart with
a numeric time axis at the bottom of the plot."""

import re
import zipfile
from xml.etree import ElementTree

import pandas as pd
from openpyxl import load_workbook

from groundstation.cli import main
from groundstation.estimation import ESTIMATORS, live_estimators
from groundstation.recording import RecordingWriter
from groundstation.sim.firmware import FirmwareSettings
from groundstation.sim.stream import Scenario, SimStream

from tests.shared_datasets import shared_dataset

CHART = "{http://schemas.openxmlformats.org/drawingml/2006/chart}"


def imu_only_recording(path):
    """A hover from firmware with no magnetometer and no GPS, recorded as the app records: every live estimator."""
    stream = SimStream(Scenario(profile="hover", duration_s=6.0, seed=5, firmware=FirmwareSettings()))
    with RecordingWriter(path, {"source": "simulated bridge", "filters": list(live_estimators())}) as writer:
        for chunk in [*stream.advance(stream.end_s), *stream.flush()]:
            writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)
    return path


def estimators_in(columns) -> set[str]:
    return {c.removesuffix("_pitch_deg") for c in columns if c.endswith("_pitch_deg")} - {"onboard", "true"}


def test_an_export_without_magnetometer_or_gps_leaves_out_the_estimators_that_need_them(tmp_path):
    source = imu_only_recording(tmp_path / "imu.gsrec")
    assert main(["export", str(source), "--out", str(tmp_path / "imu.csv")]) == 0
    exported = estimators_in(pd.read_csv(tmp_path / "imu.csv", nrows=1).columns)
    needing = {name for name in live_estimators() if ESTIMATORS[name].needs}
    assert needing and not exported & needing  # hfm would only repeat hf, ukf be a slow tilt filter
    assert exported == set(live_estimators()) - needing
    assert main(["export", str(source), "--out", str(tmp_path / "asked.csv"), "--filters", "hf,hfm"]) == 0
    assert estimators_in(pd.read_csv(tmp_path / "asked.csv", nrows=1).columns) == {"hf", "hfm"}  # asked by name


def test_the_cli_exports_a_flight_log_with_the_estimators_the_app_opens_it_with(tmp_path):
    log = shared_dataset("flightlogs/px4_sitl_quad_groundtruth.ulg")
    assert main(["export", str(log), "--out", str(tmp_path / "log.csv"), "--rate", "5"]) == 0
    exported = estimators_in(pd.read_csv(tmp_path / "log.csv", nrows=1).columns)
    assert {"ahf2", "vqf", "ahf"} <= exported  # not AHF alone: the app shows AHF2 and VQF first


def chart_xml(book) -> list[ElementTree.Element]:
    with zipfile.ZipFile(book) as archive:
        return [ElementTree.fromstring(archive.read(n)) for n in archive.namelist() if re.match(r"xl/charts/chart\d+\.xml", n)]


def test_the_workbook_charts_time_on_a_numeric_axis_labelled_at_the_bottom(sim_recording, tmp_path):
    book = tmp_path / "flight.xlsx"
    assert main(["export", str(sim_recording), "--out", str(book), "--rate", "10"]) == 0
    charts = chart_xml(book)
    assert len(charts) == 4  # pitch and roll on Chart, the spectra on Vibration: every one against a number
    for chart in charts:
        assert chart.find(f".//{CHART}scatterChart") is not None and chart.find(f".//{CHART}lineChart") is None
        axes = chart.findall(f".//{CHART}valAx")
        assert len(axes) == 2 and chart.find(f".//{CHART}catAx") is None  # time is a number, not a label per point
        assert all(axis.find(f"{CHART}tickLblPos").get("val") == "low" for axis in axes)  # at the edge, not at 0°
    for chart in charts[:2]:  # pitch and roll: the time axis spans the session
        time_axis = next(a for a in chart.findall(f".//{CHART}valAx") if a.find(f"{CHART}axPos").get("val") == "b")
        times = pd.read_excel(book, sheet_name="Chart data")["time (s)"]
        scaling = time_axis.find(f"{CHART}scaling")
        assert float(scaling.find(f"{CHART}min").get("val")) == times.iloc[0]
        assert float(scaling.find(f"{CHART}max").get("val")) == times.iloc[-1]


def session_labels(book) -> list[str]:
    sheet = load_workbook(book, read_only=True)["Session"]
    return [row[0] for row in sheet.iter_rows(values_only=True) if row and isinstance(row[0], str)]


def test_the_session_sheet_says_its_facts_in_words(sim_recording, tmp_path):
    book = tmp_path / "flight.xlsx"
    assert main(["export", str(sim_recording), "--out", str(book), "--rate", "10"]) == 0
    labels = session_labels(book)
    assert "recording format version" in labels
    assert not [label for label in labels if re.fullmatch(r"[a-z0-9]+(_[a-z0-9]+)+", label)]  # no raw keys


def test_a_mavlink_session_sheet_does_not_wait_for_a_config_frame(tmp_path):
    book = tmp_path / "tlog.xlsx"
    log = shared_dataset("flightlogs/arduplane_quadplane_sitl.tlog")
    assert main(["export", str(log), "--out", str(book), "--rate", "2"]) == 0
    sheet = load_workbook(book, read_only=True)["Session"]
    text = [str(v) for row in sheet.iter_rows(values_only=True) for v in row if v is not None]
    assert not any("no CONFIG frame" in t for t in text)
    assert "MAVLink (an autopilot)" in text


def test_an_estimator_asked_for_without_its_aiding_is_said_to_need_it(tmp_path, capsys):
    """Issue 33: ukf without GPS flips; exported when asked for by name, and one line says why to doubt it,
    as evaluate says (``estimation.unmet_needs``)."""
    source = imu_only_recording(tmp_path / "imu.gsrec")
    assert main(["export", str(source), "--out", str(tmp_path / "asked.csv"), "--filters", "hf,ukf"]) == 0
    assert estimators_in(pd.read_csv(tmp_path / "asked.csv", nrows=1).columns) == {"hf", "ukf"}
    said = [line for line in capsys.readouterr().out.splitlines() if line.startswith("warning:")]
    assert said == [f"warning: ukf needs GPS velocity and heading: without them it is a slow tilt filter whose heading drifts and can flip, and {source} has none"]

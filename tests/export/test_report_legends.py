"""The flight report's figures (issue 34): legends that do not overlap each other nor the curves, and one colour
per estimator in every figure, the app's (``groundstation.palette``). Text widths are measured by Qt's font
metrics for the page's font (an independent measure of what a browser draws), not by the figures' own estimate."""

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from PySide6 import QtGui

from groundstation.cli import main
from groundstation.estimation import label
from groundstation.export.report import report_html
from groundstation.export.report_figures import FONT_PX, line_plot
from groundstation.estimation import colour_of as estimator_colour
from groundstation.palette import ONBOARD_COLOUR
from groundstation.session_makers.load import load_session

SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def metrics(qapp):
    font = QtGui.QFont("DejaVu Sans")
    font.setPixelSize(FONT_PX)
    return QtGui.QFontMetricsF(font)


def boxes(svg: str, metrics) -> tuple[tuple[float, float, float, float], list[tuple[float, float, float, float]]]:
    """The plot area and each legend entry's box (its swatch and its text as Qt measures it): x0, y0, x1, y1."""
    root = ET.fromstring(svg)
    area = next(r for r in root.iter(f"{SVG}rect") if r.get("class") == "area")
    plot = tuple(float(area.get(k)) for k in ("x", "y"))
    plot = (*plot, plot[0] + float(area.get("width")), plot[1] + float(area.get("height")))
    entries = []
    for group in root.iter(f"{SVG}g"):
        if group.get("class") != "legend-entry":
            continue
        swatch, text = group.find(f"{SVG}line"), group.find(f"{SVG}text")
        x0 = float(swatch.get("x1"))
        tx, ty = float(text.get("x")), float(text.get("y"))
        entries.append((x0, ty - metrics.ascent(), tx + metrics.horizontalAdvance(text.text), ty + metrics.descent()))
    return plot, entries


def overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def test_long_legends_overlap_neither_each_other_nor_the_plot(metrics):
    t = np.linspace(0.0, 10.0, 200)
    names = ["onboard", "AHF2", "accel x (the second IMU)", "gyro z of the full-rate stream", "HF+mag", "SSSRUKF",
             "a label long enough to run past a fixed column of a hundred and fifty pixels", "VQF", "ECF+mag"]
    svg = line_plot([(n, t, np.sin(t + i)) for i, n in enumerate(names)], "pitch", "session time (s)", "pitch (°)")
    plot, entries = boxes(svg, metrics)
    assert len(entries) == len(names)
    width = float(ET.fromstring(svg).get("width"))
    height = float(ET.fromstring(svg).get("height"))
    for i, a in enumerate(entries):
        assert not overlap(a, plot), names[i]
        assert 0 <= a[0] and a[2] <= width and a[3] <= height, names[i]  # inside the figure
        for j, b in enumerate(entries[:i]):
            assert not overlap(a, b), (names[i], names[j])


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    path = tmp_path_factory.mktemp("legends") / "flight.gsrec"
    assert main(["simulate", "--scenario", "flight", "--duration", "20", "--seed", "2", "--out", str(path)]) == 0
    return load_session(path, filters=("ahf2", "ahf", "hf", "ecf", "vqf"), exact=True)


def test_an_estimator_keeps_its_colour_in_every_figure_of_the_report(flight):
    page = report_html(flight, "flight.gsrec")
    strokes: dict[str, set[str]] = {}
    for svg in re.findall(r"<svg.*?</svg>", page, flags=re.S):
        for line in ET.fromstring(svg).iter(f"{SVG}polyline"):
            strokes.setdefault(line.get("data-series"), set()).add(line.get("stroke").lower())
    shown = [n for n in flight.estimated if label(n) in strokes]
    assert len(shown) >= 4
    for name in shown:
        assert strokes[label(name)] == {estimator_colour(name).lower()}, name
    assert len({estimator_colour(n) for n in shown}) == len(shown)  # told apart


def test_the_onboard_estimate_is_the_apps_wine_dashed(tmp_path):
    t = np.linspace(0.0, 1.0, 10)
    svg = line_plot([("onboard", t, t, ONBOARD_COLOUR, True)], "pitch", "s", "°")
    line = next(ET.fromstring(svg).iter(f"{SVG}polyline"))
    assert line.get("stroke") == ONBOARD_COLOUR and line.get("stroke-dasharray")


def test_a_flight_logs_report_shows_its_controller_battery_gps_and_outputs(tmp_path):
    from tests.autopilot.mavlink_helpers import flightlog

    data = load_session(flightlog("arducopter_cubeorange_2023-07-06_10-12-18.bin"), filters=("ahf2",), exact=True)
    page = report_html(data, "copter.bin")
    assert "<h2>Controller, battery, GPS and outputs</h2>" in page
    titles = re.findall(r'aria-label="([^"]+)"', page)
    for title in ("Attitude: roll", "Rates: pitch rate", "Battery: voltage", "GPS: HDOP", "Outputs: outputs"):
        assert title in titles, title
    svg = next(s for s in re.findall(r"<svg.*?</svg>", page, flags=re.S) if 'aria-label="Attitude: roll"' in s)
    desired = next(line for line in ET.fromstring(svg).iter(f"{SVG}polyline") if line.get("data-series") == "desired")
    assert len(desired.get("points").split()) > 100  # every row, reduced to two a pixel column


def test_the_labels_of_close_marks_do_not_overlap(metrics):
    """A reboot at 3.6 s and a clock jump at 4.0 s of a 209 s log: their labels were drawn over each other."""
    t = np.linspace(0.0, 209.0, 500)
    marks = [(3.6, "reboot"), (4.0, "clock jump"), (4.2, "reboot"), (120.0, "reboot")]
    svg = line_plot([("AHF2", t, np.sin(t))], "pitch", "session time (s)", "pitch (°)", marks=marks)
    plot, _ = boxes(svg, metrics)
    texts = [e for e in ET.fromstring(svg).iter(f"{SVG}text") if e.text in {"reboot", "clock jump"}]
    assert len(texts) == len(marks)
    placed = [(float(e.get("x")), float(e.get("y")) - metrics.ascent(),
               float(e.get("x")) + metrics.horizontalAdvance(e.text), float(e.get("y")) + metrics.descent()) for e in texts]
    for i, a in enumerate(placed):
        assert plot[1] <= a[1] and a[3] <= plot[3]  # inside the plot area
        for b in placed[i + 1:]:
            assert not overlap(a, b), (a, b)

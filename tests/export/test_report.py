"""The flight report (``groundstation report``): a simulated flight with motor vibration and a reboot
whose report finds both; every shared flight log reported without a traceback; the page is whole
on its own (no script, no address, figures inline) and renders in a real browser (headless Chromium)."""

import html
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from groundstation.cli import main
from tests.cli_in_process import run_in_process

FLIGHTLOGS = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "flightlogs"  # as tests/autopilot finds them
SHARED_LOGS = sorted(p.name for pattern in ("*.bin", "*.ulg", "*.tlog") for p in FLIGHTLOGS.glob(pattern))
VIBRATION_HZ = 37.0
REBOOT_S = 15.0


class Page(HTMLParser):
    """The findings (their data- attributes), every tag, and the attributes that would fetch something."""

    def __init__(self, text: str):
        super().__init__()
        self.findings: list[dict] = []
        self.tags: set[str] = set()
        self.fetching: list[tuple[str, str, str]] = []
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        self.tags.add(tag)
        attrs = dict(attrs)
        if "finding" in (attrs.get("class") or "").split():
            self.findings.append(attrs)
        for name in ("src", "href", "xlink:href", "action", "poster", "data"):
            if attrs.get(name):
                self.fetching.append((tag, name, attrs[name]))


@pytest.fixture(scope="module")
def vibrating_flight(tmp_path_factory):
    """30 s of the simulated flight with motor vibration at 37 Hz (hover) and a board reboot at 15 s."""
    folder = tmp_path_factory.mktemp("report")
    path = folder / "shaky.gsrec"
    assert main(["simulate", "--duration", "30", "--vibration", str(VIBRATION_HZ), "--reboot-after", str(REBOOT_S),
                 "--out", str(path)]) == 0
    out = folder / "shaky.html"
    assert main(["report", str(path), "--out", str(out)]) == 0
    return path, out


def test_the_report_of_a_simulated_flight_finds_its_vibration_peak_and_its_reboot(vibrating_flight):
    _, out = vibrating_flight
    page = Page(out.read_text(encoding="utf-8"))
    peaks = [f for f in page.findings if f["data-kind"] == "vibration_peak"]
    assert len(peaks) == 1 and abs(float(peaks[0]["data-frequency-hz"]) - VIBRATION_HZ) <= 2.0
    reboots = [f for f in page.findings if f["data-kind"] == "reboot"]
    assert len(reboots) == 1 and abs(float(reboots[0]["data-t-s"]) - REBOOT_S) < 0.5
    assert "high" in reboots[0]["class"].split()
    order = ["high", "medium", "low"]
    ranks = [order.index(next(c for c in f["class"].split() if c in order)) for f in page.findings]
    assert ranks == sorted(ranks)  # the most severe first


def test_the_page_stands_alone(vibrating_flight):
    """Nothing to fetch: no script, no stylesheet link, no image file, no address; figures are inline SVG."""
    _, out = vibrating_flight
    text = out.read_text(encoding="utf-8")
    page = Page(text)
    assert not page.fetching and not {"script", "link", "img", "iframe", "object"} & page.tags
    assert "url(" not in text and "@import" not in text
    assert text.count("<svg") >= 4  # pitch, roll, their difference, the spectra
    for section in ("Flight", "Findings", "Attitude", "Vibration", "Link", "Events and messages"):
        assert f"<h2>{section}</h2>" in text


def test_the_report_renders_in_a_real_browser(vibrating_flight, tmp_path):
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        pytest.skip("chromium is not installed")
    from PySide6 import QtGui

    _, out = vibrating_flight
    shot = tmp_path / "report.png"
    subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                    "--window-size=900,1600", f"--screenshot={shot}", out.as_uri()], capture_output=True, timeout=120, check=True)
    image = QtGui.QImage(str(shot)).convertToFormat(QtGui.QImage.Format.Format_RGB32)
    assert image.width() == 900 and image.height() == 1600
    bgra = np.frombuffer(image.constBits(), np.uint8).reshape(image.height(), image.bytesPerLine() // 4, 4)[:, :900, :3]
    rgb = bgra[..., ::-1].astype(int)

    def near(colour: int) -> bool:
        target = np.array([(colour >> 16) & 255, (colour >> 8) & 255, colour & 255])
        return bool((np.abs(rgb - target).max(axis=-1) < 24).sum() > 50)

    # drawn on the first screen: the high finding's red bar (#c00) and the pitch plot's estimator in its app colour
    # (the simulated board records AHF)
    from groundstation.estimation import colour_of

    assert near(0xCC0000) and near(int(colour_of("ahf").lstrip("#"), 16))


@pytest.mark.parametrize("name", SHARED_LOGS)
def test_every_shared_log_gets_a_report(name, tmp_path, capsys):
    out = tmp_path / "report.html"
    result = run_in_process(capsys, "report", FLIGHTLOGS / name, "--out", out, "--filters", "ahf")
    assert result.returncode == 0 and "Traceback" not in result.stderr, result.stderr[-2000:]
    assert f"wrote {out}" in result.stdout
    assert "<h2>Findings</h2>" in out.read_text(encoding="utf-8")


def test_a_report_is_refused_before_any_work_and_leaves_no_file(vibrating_flight, tmp_path, capsys):
    path, out = vibrating_flight
    before = out.read_bytes()
    assert main(["report", str(path), "--out", str(out)]) == 2  # exists: --overwrite replaces it
    assert out.read_bytes() == before
    assert main(["report", str(path), "--out", str(tmp_path / "report.pdf")]) == 2
    assert main(["report", str(tmp_path / "missing.gsrec"), "--out", str(tmp_path / "r.html")]) == 2
    assert main(["report", str(path), "--out", str(tmp_path / "no" / "r.html")]) == 2
    assert "Traceback" not in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_the_report_says_what_the_suggested_notch_would_do(vibrating_flight):
    """The notch at the 37 Hz rotor, on the 100 Hz IMU that carries it: the spectra before and after, its Bode
    view, its phase lag at 10-30 Hz and the attitude difference, as ``analysis.whatif`` computes them."""
    from groundstation.analysis.vibration import vibration_summary
    from groundstation.analysis.whatif import what_if
    from groundstation.session_makers.load import load_session

    path, out = vibrating_flight
    text = out.read_text(encoding="utf-8")
    data = load_session(path, exact=True)
    summary = vibration_summary(data)
    change = what_if(data, "notch", summary.notch["frequency_hz"], summary.notch["bandwidth_hz"])
    assert "<h3>What the suggested notch would do</h3>" in text
    assert "spectrum before and after" in text and "the notch&#x27;s gain" in text and "the notch&#x27;s phase" in text
    for line in change.lines():
        assert html.escape(line.strip()) in text
    assert change.attitude is not None and change.spectra["accel"].attenuation_db < -3.0
    assert f'data-lag-20-hz-deg="{change.phase_lag_deg[20.0]:.6g}"' in text


def test_a_findings_figures_are_data_attributes_whatever_their_names():
    """A figure's name becomes an attribute name: one with spaces or brackets (``gap (s)``) must not break the
    tag (``data-gap (s)="1.5"`` is three attributes, one of them ``(s)``)."""
    from groundstation.export.report import findings_section
    from groundstation.export.report_findings import Finding

    found = [Finding("low", "gap", "a gap", values={"gap (s)": 1.5, "level_m_s2": 2.0, 'odd"<name>': 3.0})]
    (finding,) = Page(findings_section(found)).findings
    figures = {name: value for name, value in finding.items() if name.startswith("data-") and name != "data-kind"}
    assert figures == {"data-gap-s": "1.5", "data-level-m-s2": "2", "data-odd-name": "3"}

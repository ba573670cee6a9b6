"""``groundstation experiments``: in-process through ``groundstation.cli.main``, headless; the PNG files
read back as images, the printed tables carry the paper's figures beside ours, and seed 000's quick
numbers are checked against the simulator's truth."""

import contextlib
import io
import sys
import types

import numpy as np
import pytest

from groundstation import cli
from groundstation.experiments import EXPERIMENTS, load, seed000
from groundstation.sim.offline import simulate
from groundstation.units import STANDARD_GRAVITY_M_S2

OURS = ("seed000", "noise")
OUR_FIGURES = ("seed000_slide_pitch.png", "seed000_fast_pitch.png", "noise_gyro_adev.png", "noise_accel_adev.png")


def run_cli(*args):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = cli.main(["experiments", *args])
    return status, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def ours(tmp_path_factory):
    folder = tmp_path_factory.mktemp("experiments") / "new" / "folder"  # created by the command
    status, out, err = run_cli("--out", str(folder), "--quick", "--only", ",".join(OURS))
    return folder, status, out, err


def image_pixels(path):
    from PySide6 import QtGui

    image = QtGui.QImage(str(path))
    assert not image.isNull(), f"{path} is not an image Qt can read"
    image = image.convertToFormat(QtGui.QImage.Format.Format_RGB32)
    # A copy: the buffer belongs to the QImage, freed when this function returns.
    rows = np.frombuffer(image.constBits(), np.uint8).reshape(image.height(), image.bytesPerLine()).copy()
    return rows[:, : 4 * image.width()].reshape(image.height(), image.width(), 4)[..., :3]


def test_figures_are_real_pngs_with_curves_on_them(ours):
    folder, status, out, err = ours
    assert status == 0, err
    for name in OUR_FIGURES:
        path = folder / name
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        pixels = image_pixels(path)
        assert pixels.shape[0] >= 300 and pixels.shape[1] >= 500
        drawn = (pixels < 250).any(axis=-1)
        assert 0.01 < drawn.mean() < 0.6, f"{name}: {drawn.mean():.3f} of the pixels drawn"
        colours = {tuple(c) for c in pixels[drawn][:: 7].tolist()}
        assert len(colours) > 20  # several coloured curves and black text, not one flat fill
        assert str(path) in out  # listed under "files written"


def test_tables_printed_and_written_with_the_papers_figures_beside_ours(ours):
    folder, status, out, err = ours
    for title in ("Static", "Normal flight", "Horizontal sliding", "Fast attitude change", "Gyroscope at rest"):
        assert title in out
    for paper in ("0.05 (AHF vs accelerometer)", "0.523 / 0.498", "lowest", "0.005", "400"):
        assert paper in out
    markdown = (folder / "tables.md").read_text(encoding="utf-8")
    assert "| filter | pitch MAE (deg) | roll MAE (deg) |" in markdown
    assert "![seed000_fast_pitch.png](seed000_fast_pitch.png)" in markdown
    assert out.index("== seed000") < out.index("== noise")  # in the order asked
    assert "Traceback" not in out + err


@pytest.fixture(scope="module")
def seed000_quick():
    result = seed000.run(quick=True)
    return {table.title.split(",")[0]: table for table in result.tables}


def rows_by_filter(table):
    return {row[0]: row[1:] for row in table.rows}


def test_static_errors_are_small_against_the_truth(seed000_quick):
    rows = rows_by_filter(seed000_quick["Static"])
    # The simulated part: cross-axis ±2 % (3σ) tilts the accelerometer's gravity by well under 1.5°; the
    # filters add at most the AHF's hop of about 1°.
    accel_pitch, accel_roll = rows["accelerometer angle"][2:4]
    assert max(accel_pitch, accel_roll) < 1.5
    for name, (_, _, pitch, roll, _) in rows.items():
        assert pitch < accel_pitch + 1.0 and roll < accel_roll + 1.0, name
    assert rows["HF"][0] < 0.2 and rows["EKF"][0] < 0.2  # smooth filters sit on the accelerometer's mean


def test_slide_errors_stay_within_the_accelerometers_apparent_tilt(seed000_quick):
    sim = simulate("slide", seed000.QUICK_DURATION_S["slide"], seed000.SEED)
    apparent_deg = np.degrees(np.arctan(np.abs(sim.truth.acc_ned_m_s2[:, 0]) / STANDARD_GRAVITY_M_S2))
    for name, (pitch, roll, _, _) in rows_by_filter(seed000_quick["Horizontal sliding"]).items():
        assert 0.2 < pitch < apparent_deg.mean() + 1.0, name  # the slide shows in pitch, no more than the tilt it fakes
        assert roll < 1.0, name  # slid along north only: roll sees nothing but noise (and the AHF's hop)


def test_fast_flips_ahf_keeps_up_with_the_truth_and_hf_lags(seed000_quick):
    rows = rows_by_filter(seed000_quick["Fast attitude change"])
    truth_rise = rows["truth"][0]
    assert 0.03 < truth_rise < 0.3  # the profile's flips: 45-80° at 550-900 °/s
    assert rows["AHF"][0] < 1.3 * truth_rise
    assert rows["AHF"][3] < 0.5  # median recovery to within 2° after the flip ends
    assert rows["HF"][0] > 2.0 * truth_rise


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--only", "seed000,nope"], "unknown experiment nope; choose from seed000"),
        (["--only", ","], "unknown experiment nothing"),
    ],
)
def test_unknown_experiment_is_a_clear_error(tmp_path, args, message):
    status, out, err = run_cli("--out", str(tmp_path), *args)
    assert status == 2
    assert message in err and "Traceback" not in err


def test_unwritable_output_folder_is_a_clear_error(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    status, out, err = run_cli("--out", str(blocker / "figures"), "--only", "noise", "--quick")
    assert status == 2
    assert "cannot write into the output folder" in err and str(blocker / "figures") in err
    assert "Traceback" not in err and "==" not in out  # refused before any experiment ran


def test_a_failing_experiment_is_reported_and_the_others_still_run(tmp_path, monkeypatch):
    broken = types.ModuleType("broken_experiment")
    broken.NAME, broken.TITLE = "broken", "always fails"

    def run(quick):
        raise RuntimeError("deliberately broken")

    broken.run = run
    monkeypatch.setitem(sys.modules, "broken_experiment", broken)
    monkeypatch.setitem(EXPERIMENTS, "broken", "broken_experiment")
    status, out, err = run_cli("--out", str(tmp_path), "--only", "broken,noise", "--quick")
    assert status == 1
    assert "broken failed: RuntimeError: deliberately broken" in err
    assert (tmp_path / "noise_gyro_adev.png").exists()
    assert "**failed**: RuntimeError: deliberately broken" in (tmp_path / "tables.md").read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def every_result():
    return {name: load(name).run(quick=True) for name in EXPERIMENTS if name not in OURS}


def test_every_registered_experiment_runs_quick_and_keeps_the_report_contract(every_result, tmp_path):
    from groundstation.ui.figures import write_png

    filenames = list(OUR_FIGURES)
    for name, result in every_result.items():
        module = load(name)
        assert module.NAME == name and module.TITLE
        assert result.tables, f"{name} has no table"
        for table in result.tables:
            assert all(len(row) == len(table.columns) for row in table.rows), f"{name}: {table.title}"
            assert table.format().startswith(table.title)
        for figure in result.figures:
            assert figure.filename.endswith(".png")
            for series in figure.series:
                assert len(series.x) == len(series.y), f"{name}: {figure.filename} {series.label}"
            write_png(figure, tmp_path / figure.filename)
            assert (tmp_path / figure.filename).stat().st_size > 1000
            filenames.append(figure.filename)
    assert len(filenames) == len(set(filenames)), "two experiments write the same figure file"

"""The desktop bundle (bundle/build.py, PyInstaller): built here for Linux, it starts the app on its
demo offscreen for 10 s with no traceback, answers --help, and exports a recording to the same file as
the installed package. Minutes of building: marked ``slow``, outside the README's test command;
``pytest -m slow tests/bundle`` runs it."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def executable(tmp_path_factory):
    """The bundle built now, or one built already named by $GROUNDSTATION_BUNDLE (its executable)."""
    if os.environ.get("GROUNDSTATION_BUNDLE"):
        return Path(os.environ["GROUNDSTATION_BUNDLE"])
    pytest.importorskip("PyInstaller")
    folder = tmp_path_factory.mktemp("bundle")
    done = subprocess.run([sys.executable, str(ROOT / "bundle" / "build.py"), "--dist", str(folder / "dist"),
                           "--work", str(folder / "work")], capture_output=True, text=True, timeout=1800)
    assert done.returncode == 0, done.stderr[-3000:]
    path = folder / "dist" / "groundstation" / "groundstation"
    assert path.is_file()
    return path


def environment(tmp_path):
    return {**os.environ, "QT_QPA_PLATFORM": "offscreen", "GROUNDSTATION_RECORDINGS": str(tmp_path / "recordings"),
            "XDG_CONFIG_HOME": str(tmp_path / "config"), "HOME": str(tmp_path)}


def test_the_app_runs_its_demo_for_ten_seconds(executable, tmp_path):
    process = subprocess.Popen([str(executable), "app", "--demo"], env=environment(tmp_path), stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    deadline = time.monotonic() + 600  # a first start compiles the estimators' kernels (a minute or more)
    while not list((tmp_path / "recordings").glob("*.gsrec")) and time.monotonic() < deadline and process.poll() is None:
        time.sleep(1)
    time.sleep(10)  # ten seconds of the demo
    assert process.poll() is None, process.communicate()[1]
    process.send_signal(signal.SIGTERM)
    out, err = process.communicate(timeout=60)
    assert "Traceback" not in err and "Error" not in err, err
    recordings = list((tmp_path / "recordings").glob("*.gsrec"))
    assert recordings and recordings[0].stat().st_size > 10_000  # the demo streamed and was recorded


def test_help_and_an_export_equal_to_the_installed_package(executable, tmp_path):
    done = subprocess.run([str(executable), "--help"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "export" in done.stdout
    recording = tmp_path / "flight.gsrec"
    subprocess.run([sys.executable, "-m", "groundstation", "simulate", "--scenario", "hover", "--duration", "10",
                    "--out", str(recording)], check=True, cwd=ROOT, timeout=300)
    bundled, installed = tmp_path / "bundled.csv", tmp_path / "installed.csv"
    done = subprocess.run([str(executable), "export", str(recording), "--out", str(bundled), "--filters", "ahf,hf,vqf"],
                          capture_output=True, text=True, timeout=600, env=environment(tmp_path))
    assert done.returncode == 0, done.stderr
    subprocess.run([sys.executable, "-m", "groundstation", "export", str(recording), "--out", str(installed),
                    "--filters", "ahf,hf,vqf"], check=True, cwd=ROOT, timeout=600)
    assert bundled.read_bytes() == installed.read_bytes()  # the same code, the same NumPy: the same bytes

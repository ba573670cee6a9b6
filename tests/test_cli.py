"""The console script as a user runs it: a real process, its exit status and its output."""

import ast
import os
import subprocess
import sys

import pytest

from groundstation.cli import COMMANDS, main


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "groundstation", *args], capture_output=True, text=True, timeout=120)


def test_help_lists_every_subcommand():
    result = run_cli("--help")
    assert result.returncode == 0
    for name in COMMANDS:
        assert name in result.stdout


def test_each_subcommand_has_its_own_help():
    for name in COMMANDS:
        result = run_cli(name, "--help")
        assert result.returncode == 0, result.stderr
        assert f"groundstation {name}" in result.stdout


def test_unknown_option_is_a_usage_error_not_a_traceback():
    result = run_cli("protocol", "--no-such-option")
    assert result.returncode == 2
    assert "Traceback" not in result.stderr


def test_a_garbled_port_spec_is_refused_before_any_window_opens():
    headless = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM")}
    result = subprocess.run([sys.executable, "-m", "groundstation", "app", "--port", "htp://192.168.4.1:23"],
                            capture_output=True, text=True, timeout=120, env=headless)
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert "unknown source scheme 'htp:'" in result.stderr
    for form in ("udp://HOST:PORT", "tcp://HOST:PORT", "sim:", "FILE.gsrec", "COM3"):
        assert form in result.stderr  # the message lists what would have worked
    assert "no display" not in result.stderr  # said before the app looked for a display (on Linux it has none here)


def test_evaluate_and_export_of_a_recording_report_real_progress(tmp_path, capsys, monkeypatch):
    """The bars of the batch path's progress (shown at once here instead of after a second), to 100 %."""
    import groundstation.commands.progress as progress
    import groundstation.session_makers.batch as batch

    monkeypatch.setattr(progress, "SHOW_AFTER_S", 0.0)
    # the decode reports once a piece: pieces of 4 kB make a 5 s recording's bar move as an hour's 2 MB ones do
    monkeypatch.setattr(batch, "PIECE_BYTES", 4096)
    path = tmp_path / "flight.gsrec"
    assert main(["simulate", "--duration", "5", "--out", str(path)]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(path), "--filters", "ahf"]) == 0
    bars = capsys.readouterr().err.split("\r")
    assert any(b.startswith("computing [") for b in bars) and "100%" in bars[-1]
    fractions = [int(b.split("]")[1].split("%")[0]) for b in bars if b.startswith("computing [")]
    assert fractions == sorted(fractions) and len(set(fractions)) > 2  # it moves, never back
    assert main(["export", str(path), "--out", str(tmp_path / "out.csv")]) == 0
    assert "decoding [" in capsys.readouterr().err


def test_import_reports_progress_and_keeps_every_value(tmp_path, capsys, monkeypatch):
    import gzip

    import numpy as np
    import pandas as pd

    import groundstation.commands.progress as progress
    from groundstation.recording import open_recording

    import groundstation.commands.import_csv as import_csv

    monkeypatch.setattr(progress, "SHOW_AFTER_S", 0.0)
    monkeypatch.setattr(import_csv, "ROWS_PER_BLOCK", 500)
    assert main(["simulate", "--duration", "30", "--scenario", "static", "--out", str(tmp_path / "raw.bin")]) == 0
    truth = tmp_path / "raw.truth.csv.gz"
    capsys.readouterr()
    assert main(["import", str(truth), "--out", str(tmp_path / "trial.gsrec")]) == 0
    bars = [b for b in capsys.readouterr().err.split("\r") if b.startswith("importing [")]
    assert len(bars) > 1 and "100%" in bars[-1]  # more than one block of rows: it moved
    with gzip.open(truth) as f:
        expected = pd.read_csv(f)
    samples = open_recording(tmp_path / "trial.gsrec").samples
    for name in expected.columns:
        assert np.array_equal(samples[name], expected[name].to_numpy(dtype=float), equal_nan=True), name


def test_every_command_that_opens_any_file_says_so_in_its_one_line_help():
    """A command whose FILE takes every format (its argument's help is ``formats.described()``) names
    each of them where a user first looks: ``groundstation --help`` and the top of its own ``--help``."""
    from groundstation import formats
    from groundstation.cli import build_parser

    everything = formats.described()
    takers = []
    overview = run_cli("--help").stdout
    for name, (_, one_line) in COMMANDS.items():
        result = run_cli(name, "--help")
        assert result.returncode == 0, result.stderr
        if everything not in " ".join(result.stdout.split()):
            continue
        takers.append(name)
        for what in ("recording", "dataset CSV", *(s for f in formats.flight_logs() for s in f.suffixes)):
            assert what in one_line, f"'groundstation {name} --help' takes {what} but its help does not say so"
        assert " ".join(one_line.split()) in " ".join(result.stdout.split())
    assert {"app", "evaluate", "replay", "export", "report"} <= set(takers)
    assert "recording or dataset CSV" not in overview and build_parser() is not None


def test_export_help_lists_every_format_of_the_one_registry():
    """The formats an export writes are ``export.request.FORMATS``; ``groundstation --help`` and
    ``groundstation export --help`` name each of them (MCAP too) with its suffix."""
    from groundstation.export.request import FORMATS

    overview = " ".join(run_cli("--help").stdout.split())
    own = " ".join(run_cli("export", "--help").stdout.split())
    for suffix, export_format in FORMATS.items():
        name = export_format.name
        assert name in overview, f"'groundstation --help' does not name {name}"
        assert f"OUT{suffix}" in own and name in own, f"'groundstation export --help' does not list {suffix}"


HEAVY = ("numpy", "numba", "pandas", "pyarrow", "PySide6", "scipy", "openpyxl")


# The simulator's options are its settings' defaults (``sim/settings.py``), whose validation needs the
# mounting matrices and the protocol's modes: numpy, imported with ``groundstation.mounting``.
NEEDS_NUMPY_FOR_HELP = {"simulate", "bridge-sim"}


@pytest.mark.parametrize("argv", [[], *([name] for name in COMMANDS)], ids=lambda argv: " ".join(argv) or "top")
def test_help_imports_none_of_the_heavy_libraries(argv):
    # Help is read before anything runs: it should not wait seconds for numba's compiler or Qt. Each
    # command in a process of its own, as a user runs it.
    probe = ("import sys\nfrom groundstation.cli import main\n"
             f"try:\n    main({[*argv, '--help']!r})\nexcept SystemExit:\n    pass\n"
             f"print(sorted(m for m in {HEAVY!r} if m in sys.modules), file=sys.stderr)")
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    allowed = {"numpy"} if set(argv) & NEEDS_NUMPY_FOR_HELP else set()
    assert set(ast.literal_eval(result.stderr.strip())) <= allowed, result.stderr


def test_the_estimator_registry_names_its_classes_by_their_own_names():
    from groundstation.estimation import ESTIMATORS

    assert [cls.name for cls in ESTIMATORS.values()] == list(ESTIMATORS)


def test_what_the_registry_says_of_an_estimator_without_importing_it_is_what_its_class_says():
    """``about`` (help, the window's first paint) and the imported class agree on every fact."""
    from groundstation.estimation import ESTIMATORS, about

    for name, cls in ESTIMATORS.items():
        facts = about(name)
        assert (facts.module, facts.class_name) == (cls.__module__.rpartition(".")[2], cls.__name__)
        assert (facts.label, facts.colour, facts.needs, facts.live, facts.tunable) == (cls.label, cls.colour, cls.needs, cls.live, cls.tunable)


def test_the_port_helps_and_the_error_list_every_source_form_of_the_one_registry(monkeypatch, capsys):
    """The forms ``--port`` takes are ``sources.spec.SCHEMES``: a scheme registered (here, for the test) is in
    ``app --help`` and ``record --help`` (which records live sources only: no recording) with no other edit."""
    from groundstation.sources import SCHEMES, SourceError, parse_spec
    from groundstation.sources.spec import SourceScheme

    monkeypatch.setitem(SCHEMES, "can", SourceScheme("groundstation.sources.udp", ("can:IFACE",), "a CAN bus adapter"))
    helps = {}
    for command in ("app", "record"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        helps[command] = "".join(capsys.readouterr().out.split())
    for name, scheme in SCHEMES.items():
        for form in scheme.forms:
            assert form in helps["app"], f"'groundstation app --help' does not list {form}"
            assert (form in helps["record"]) == (name != "recording"), form
    with pytest.raises(SourceError, match="can:IFACE  —  a CAN bus adapter"):
        parse_spec("nonsense://x")

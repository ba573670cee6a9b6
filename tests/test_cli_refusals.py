"""Command lines that cannot be meant are refused at once: exit status 2 and one line that says why,
never a traceback, a run that grows without bound, or a file destroyed (issue 22, "The command line")."""

import os
import sys

import pytest

from groundstation.cli import main

# (command line, words the message must carry). {tmp} is the test's own folder.
WRONG_COMMAND_LINES = [
    ("simulate --duration inf --out {tmp}/x.gsrec", "--duration"),
    ("simulate --duration 1e9 --out {tmp}/x.gsrec", "--duration"),
    ("simulate --duration nan --out {tmp}/x.gsrec", "--duration"),
    ("simulate --seed -1 --duration 1 --out {tmp}/x.gsrec", "seed"),
    ("simulate --sample-jitter-us -5 --duration 1 --out {tmp}/x.gsrec", "jitter"),
    ("simulate --sample-jitter-us inf --duration 1 --out {tmp}/x.gsrec", "jitter"),
    ("simulate --clock-drift-ppm 1e9 --duration 1 --out {tmp}/x.gsrec", "drift"),
    ("simulate --dropout-every 0 --duration 1 --out {tmp}/x.gsrec", "--dropout-every"),
    ("simulate --latency-ms inf --duration 1 --out {tmp}/x.gsrec", "latency_ms"),
    ("bridge-sim --udp 127.0.0.1:99999 --duration 1", "65535"),
    ("bridge-sim --udp 127.0.0.1:0 --duration 1", "65535"),
    ("evaluate {tmp}/flight.gsrec --filters ,", "--filters"),
    ("export {tmp}/flight.gsrec --out {tmp}/y.csv --filters ''", "--filters"),
    ("import {tmp}/flight.gsrec --out {tmp}/flight.tlog", "MAVLink"),
    ("protocol --decode /dev/zero", "not a file"),
    ("vibration {tmp}/missing.bin", "no such file"),
    ("vibration {tmp}/flight.gsrec --from 1.5 --to 1", "--from"),
    ("vibration {tmp}/flight.gsrec --from 0.5 --to 0.7", "too few samples"),
    ("vibration {tmp}/flight.gsrec --what-if notch --what-if-hz 0", "frequency"),
]


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cli")
    assert main(["simulate", "--duration", "2", "--out", str(tmp / "flight.gsrec")]) == 0
    return tmp


@pytest.mark.parametrize(("line", "words"), WRONG_COMMAND_LINES, ids=[line.split(" --out")[0] for line, _ in WRONG_COMMAND_LINES])
def test_a_wrong_command_line_is_refused_with_one_clear_line(folder, capsys, line, words):
    argv = [arg.strip("'") for arg in line.format(tmp=folder).split()]
    try:
        status = main(argv)
    except SystemExit as stop:  # argparse's own refusal (a bad type)
        status = stop.code
    err = capsys.readouterr().err
    assert status == 2, err
    assert "Traceback" not in err
    assert words in err
    assert not (folder / "x.gsrec").exists() and not (folder / "flight.tlog").exists()


@pytest.mark.skipif(os.name != "posix", reason="bridge-sim's pty link is POSIX only")
def test_bridge_sim_link_never_removes_a_file_it_did_not_create(tmp_path, capsys):
    precious = tmp_path / "notes.txt"
    precious.write_text("flight notes")
    assert main(["bridge-sim", "--duration", "0.2", "--link", str(precious)]) == 2
    assert "choose a new name for --link" in capsys.readouterr().err
    assert precious.read_text() == "flight notes"  # neither replaced by a symlink nor removed


@pytest.mark.skipif(os.name != "posix", reason="bridge-sim's pty link is POSIX only")
def test_bridge_sim_link_it_made_is_removed_at_exit(tmp_path):
    link = tmp_path / "ttySIM0"
    assert main(["bridge-sim", "--duration", "0.2", "--link", str(link)]) == 0
    assert not os.path.lexists(link)

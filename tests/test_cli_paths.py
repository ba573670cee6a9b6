"""Every path mistake of every command is one line and exit status 2, before any long work (issue 37):
an output folder that is read-only, a file, or under a file; a link in a folder of logs that points to
itself; an input that is missing; and nothing is left behind."""

import os
import shutil
import subprocess

import pytest

from groundstation.cli import main


@pytest.fixture(scope="module")
def places(tmp_path_factory):
    """A recording, a folder of logs with it, a plain file and a read-only folder."""
    tmp = tmp_path_factory.mktemp("paths")
    assert main(["simulate", "--duration", "2", "--out", str(tmp / "flight.gsrec")]) == 0
    (tmp / "logs").mkdir()
    shutil.copy(tmp / "flight.gsrec", tmp / "logs" / "flight.gsrec")
    (tmp / "afile").write_text("a file, not a folder")
    read_only = tmp / "read_only"
    read_only.mkdir()
    read_only.chmod(0o555)
    if _writable(read_only) and shutil.which("chattr"):  # root writes through permission bits; not through +i
        subprocess.run(["chattr", "+i", str(read_only)], capture_output=True)
    if _writable(read_only):
        pytest.skip("no way to make a folder read-only for this user here")
    yield tmp
    subprocess.run(["chattr", "-i", str(read_only)], capture_output=True)
    read_only.chmod(0o755)


def _writable(folder) -> bool:
    try:
        (folder / "probe").mkdir()
    except OSError:
        return False
    (folder / "probe").rmdir()
    return True


# (command line, words the one line carries); {tmp}: the module's folder
PATH_MISTAKES = [
    ("evaluate {tmp}/logs --out {tmp}/afile", "is a file"),
    ("evaluate {tmp}/logs --out {tmp}/afile/out", "cannot write"),
    ("evaluate {tmp}/logs --out {tmp}/read_only/out", "cannot write"),
    ("evaluate {tmp}/logs --out {tmp}/read_only", "cannot write"),
    ("report {tmp}/logs --out {tmp}/afile", "is a file"),
    ("report {tmp}/logs --out {tmp}/read_only/out", "cannot write"),
    ("report {tmp}/logs --out {tmp}/afile/out", "cannot write"),
    ("report {tmp}/flight.gsrec --out {tmp}/read_only/r.html", "cannot write"),
    ("report {tmp}/flight.gsrec --out {tmp}/afile/r.html", "cannot write"),
    ("export {tmp}/flight.gsrec --out {tmp}/read_only/x.csv", "cannot write"),
    ("export {tmp}/flight.gsrec --out {tmp}/read_only/x.mcap", "cannot write"),
    ("export {tmp}/flight.gsrec --out {tmp}/afile/x.parquet", "cannot write"),
    ("export {tmp}/missing.gsrec --out {tmp}/x.csv", "no such file"),
    ("evaluate {tmp}/missing.gsrec", "no such file"),
    ("replay {tmp}/missing.ulg", "no such file"),
    ("vibration {tmp}/missing.bin", "no such file"),
    ("import {tmp}/missing.csv --out {tmp}/x.gsrec", "no such file"),
    ("protocol --decode {tmp}/missing.bin", "not a file"),
    ("simulate --duration 1 --out {tmp}/read_only/x.gsrec", "cannot write"),
    ("simulate --duration 1 --out {tmp}/afile/x.gsrec", "cannot write"),
    ("experiments --quick --only noise --out {tmp}/read_only/e", "cannot write"),
    ("record --port sim:?scenario=hover --duration 1 --recordings {tmp}/read_only", "cannot write"),
]


@pytest.mark.parametrize(("line", "words"), PATH_MISTAKES, ids=[line for line, _ in PATH_MISTAKES])
def test_a_path_mistake_is_one_line_and_status_2(places, capsys, line, words):
    before = sorted(p.name for p in places.iterdir())
    status = main(line.format(tmp=places).split())
    err = capsys.readouterr().err
    assert status == 2, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert words in err, err
    assert sorted(p.name for p in places.iterdir()) == before  # nothing left behind, no staging folder


def test_a_link_to_itself_in_a_folder_of_logs_is_named_in_one_line(places, tmp_path, capsys):
    logs = tmp_path / "logs"
    logs.mkdir()
    shutil.copy(places / "flight.gsrec", logs)
    os.symlink("loop.ulg", logs / "loop.ulg")
    for command in ("evaluate", "report"):
        assert main([command, str(logs), "--out", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err
        assert "loop.ulg" in err and "leads nowhere" in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists()
    os.symlink("out", tmp_path / "out")  # OUT a link to itself
    os.unlink(logs / "loop.ulg")
    assert main(["evaluate", str(logs), "--out", str(tmp_path / "out")]) == 2
    assert "a link to none" in capsys.readouterr().err
    assert main(["evaluate", str(logs), "--out", str(tmp_path / "out" / "dataset")]) == 2  # a loop on the way
    assert "leads to itself" in capsys.readouterr().err

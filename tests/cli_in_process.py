"""A command run in the test's own process through ``groundstation.cli.main``, with what a process would
give: its exit status (argparse's usage errors included) and what it printed, a background thread's
traceback among it. A new interpreter per call costs seconds of imports (and of loading the compiled
estimators); the console script's own process, its ``python -m groundstation`` entry and exit status, is
tested in tests/test_cli.py."""

import subprocess
import sys
import threading

from groundstation.cli import main


def run_in_process(capsys, *args) -> subprocess.CompletedProcess:
    argv = [str(a) for a in args]
    capsys.readouterr()  # what the test printed before is not the command's
    # Python's own hooks, which print a thread's uncaught exception (or one Python could only ignore) to
    # stderr as a process does; pytest's would turn it into a warning the test's "Traceback" check misses.
    hooks = threading.excepthook, sys.unraisablehook
    threading.excepthook, sys.unraisablehook = threading.__excepthook__, sys.__unraisablehook__
    try:
        returncode = main(argv)
    except SystemExit as stop:  # argparse refusing the options: status 2, as from a process
        returncode = stop.code
    finally:
        threading.excepthook, sys.unraisablehook = hooks
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(argv, returncode, out, err)

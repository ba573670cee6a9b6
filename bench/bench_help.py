"""Start-up cost of the command line: ``groundstation --help`` and every command's ``--help`` against ``python -c pass``.

CPU seconds (user + system) of each child process, median of ``--repeats`` runs, so other work on the
machine weighs less than on a wall clock. Run from the worktree root: ``python bench/bench_help.py``.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys

from groundstation.cli import COMMANDS

CASES = {
    "python -c pass (baseline)": ["-c", "pass"],
    "groundstation --help": ["-m", "groundstation", "--help"],
    **{f"groundstation {name} --help": ["-m", "groundstation", name, "--help"] for name in COMMANDS},
}


# Byte code written and read, as an installed package has it (pip compiles it at install): with
# PYTHONDONTWRITEBYTECODE set, as on the machine these figures come from, every start compiled every module.
ENV = {**{k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}, "PYTHONPATH": os.getcwd()}


def child_cpu_s(argv: list[str]) -> float:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, *argv], check=True, stdout=subprocess.DEVNULL, env=ENV)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    print(f"| command | CPU s (median of {args.repeats}) |\n|---|---|")
    for label, argv in CASES.items():
        child_cpu_s(argv)  # warm the file cache and the byte-code cache
        print(f"| {label} | {statistics.median(child_cpu_s(argv) for _ in range(args.repeats)):.3f} |", flush=True)


if __name__ == "__main__":
    main()

"""``groundstation experiments --out DIR [--only NAME,...] [--quick]``: the seed papers' experiments on
the simulator (``groundstation.experiments.EXPERIMENTS``).

Runs each experiment in order, printing its tables (ours beside the paper's, with notes) as it
finishes; writes its figures as PNG files into DIR and every table into ``DIR/tables.md``, then lists
the files written. An experiment that fails is reported (its error and where it was raised) and the
others still run; the exit status is then 1.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import traceback
from pathlib import Path

from groundstation.errors import UserError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from groundstation.experiments import EXPERIMENTS

    parser.add_argument("--out", required=True, metavar="DIR", help="folder for the PNG figures and tables.md (created if missing)")
    parser.add_argument("--only", metavar="NAME[,NAME...]", help=f"run only these experiments, of: {', '.join(EXPERIMENTS)}")
    parser.add_argument("--quick", action="store_true", help="short simulated runs (seconds), not the papers' durations")


def run(args: argparse.Namespace) -> int:
    from groundstation.experiments import EXPERIMENTS, load

    names = _chosen(args.only, list(EXPERIMENTS))
    out = _output_folder(args.out)
    from groundstation.ui.figures import write_png  # Qt, imported only once there is work for it

    written: list[Path] = []
    sections: list[str] = []
    failed: list[str] = []
    for name in names:
        started = time.perf_counter()
        try:
            module = load(name)
            print(f"== {name}: {module.TITLE}", flush=True)
            result = module.run(quick=args.quick)
            for table in result.tables:
                print(table.format() + "\n", flush=True)
            figures = [write_png(figure, out / figure.filename) for figure in result.figures]
        except Exception as error:  # one experiment's failure must not cost the others' results
            failed.append(name)
            print(f"groundstation experiments: {name} failed: {_describe(error)}", file=sys.stderr, flush=True)
            sections.append(f"## {name}\n\n**failed**: {_describe(error)}\n")
            continue
        written += figures
        sections.append(_markdown_section(name, module.TITLE, result.tables, figures))
        print(f"({name} done in {time.perf_counter() - started:.1f} s)\n", flush=True)
    tables_md = out / "tables.md"
    try:
        tables_md.write_text("# Experiments\n\n" + "\n".join(sections), encoding="utf-8")
    except OSError as error:
        raise UserError(f"cannot write {tables_md}: {error.strerror or error}") from None
    written.append(tables_md)
    print("files written:")
    for path in written:
        print(f"  {path}")
    if failed:
        print(f"groundstation experiments: failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


def _chosen(only: str | None, known: list[str]) -> list[str]:
    """The experiments ``--only`` names (in its order, once each), else all; UserError on an unknown one."""
    if only is None:
        return known
    names = list(dict.fromkeys(n.strip() for n in only.split(",") if n.strip()))
    unknown = [n for n in names if n not in known]
    if unknown or not names:
        given = ", ".join(unknown) if unknown else "nothing"
        raise UserError(f"--only: unknown experiment {given}; choose from {', '.join(known)}")
    return names


def _output_folder(path: str) -> Path:
    """``path`` created if missing and proved writable (before minutes of work), else UserError."""
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as error:
        raise UserError(f"cannot write into the output folder {out}: {error.strerror or error}") from None
    return out


def _describe(error: Exception) -> str:
    """``Type: message (at file:line)``, the line being where it was raised."""
    frames = traceback.extract_tb(error.__traceback__)
    where = f" (at {frames[-1].filename}:{frames[-1].lineno})" if frames else ""
    return f"{type(error).__name__}: {error}{where}"


def _markdown_section(name: str, title: str, tables, figures: list[Path]) -> str:
    lines = [f"## {name}: {title}", ""]
    for table in tables:
        lines += table.markdown()
    lines += [f"![{figure.name}]({figure.name})" for figure in figures]
    return "\n".join(lines) + "\n"

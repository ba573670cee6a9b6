"""``groundstation import``: a dataset CSV (the raw-IMU layout, plain or .gz) to a recording, or a
recorded MAVLink session to a standard ``.tlog`` (Mission Planner and QGroundControl open it).

The samples are stored bit for bit, so replay, export and evaluate give exactly the numbers the
CSV gives; truth columns are kept. Flight logs (.tlog, .bin, .ulg) need no import: replay, export
and evaluate read them as they are.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

ROWS_PER_BLOCK = 50_000  # rows read between progress reports


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", metavar="FILE", help="dataset CSV (.csv or .csv.gz): time_s, gyr_*_rad_s, acc_*_m_s2, ...; "
                                                     "or a recording (.gsrec) of a MAVLink session, with --out FILE.tlog")
    parser.add_argument("--out", required=True, type=Path, metavar="FILE", help="the recording to write (.gsrec), or FILE.tlog")


def run(args: argparse.Namespace) -> int:
    import pandas as pd

    from groundstation import formats
    from groundstation.commands.progress import ProgressBar
    from groundstation.datasets import DatasetError, read_csv
    from groundstation.errors import UserError
    from groundstation.export.files import atomic_recording
    from groundstation.recording import EXTENSION
    from groundstation.text import clean

    if args.out.exists():
        raise UserError(f"{args.out} exists; choose another name")
    file_format = formats.sniff(args.file)
    if file_format is not None and file_format.read is not None:
        raise UserError(f"{args.file} is a flight log: no import needed; export, evaluate and the app's Open read it directly")
    if args.out.suffix.lower() == ".tlog":
        return save_tlog(Path(args.file), args.out)
    if args.out.suffix.lower() != EXTENSION:
        raise UserError(f"--out must end in {EXTENSION} (a recording) or .tlog (a recorded MAVLink session), "
                        f"not {args.out.name}")
    try:
        read_csv(args.file)  # the same checks and messages as evaluate
    except DatasetError as error:
        raise UserError(str(error)) from None
    bar = ProgressBar("importing")
    try:
        frame = read_with_progress(Path(args.file), bar)
    finally:
        bar.done()
    columns = {name: pd.to_numeric(frame[name], errors="coerce").to_numpy(dtype=float) for name in frame.columns}
    # Where the trial's time starts, kept apart from the rows: a lost first block must not move the rest.
    metadata = {"source": f"imported from {Path(args.file).name}", "time_origin_s": float(columns["time_s"][0])}
    with atomic_recording(args.out, metadata) as writer:
        writer.write_samples(columns)
    columns_said = ", ".join(map(str, frame.columns))
    print(clean(f"wrote {args.out}: {len(frame)} samples, columns {columns_said}", visible=True))  # the file's names
    return 0


def read_with_progress(path: Path, progress):
    """The CSV (gzip or not) as one DataFrame, read in blocks of rows; ``progress(bytes read, file size)``."""
    import gzip

    import pandas as pd

    with open(path, "rb") as raw:
        size = os.fstat(raw.fileno()).st_size
        handle = gzip.GzipFile(fileobj=raw) if raw.read(2) == b"\x1f\x8b" else raw
        raw.seek(0)
        parts = []
        for part in pd.read_csv(handle, chunksize=ROWS_PER_BLOCK):
            parts.append(part)
            progress(raw.tell(), size)
    progress(size, size)
    return pd.concat(parts, ignore_index=True)


def save_tlog(recording_path: Path, out: Path) -> int:
    from groundstation.autopilot.tlog import recording_to_tlog
    from groundstation.recording import open_recording

    recording = open_recording(recording_path)
    count = recording_to_tlog(recording, out)
    for finding in recording.damage:
        print(f"warning: {finding}")
    print(f"wrote {out}: {count} MAVLink packets")
    return 0

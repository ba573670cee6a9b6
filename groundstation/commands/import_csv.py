"""``groundstation import``: a dataset CSV (the raw-IMU layout, plain or .gz) to a recording.

The samples are stored bit for bit, so replay, export and evaluate give exactly the numbers the
CSV gives; truth columns are kept.
"""

from __future__ import annotations

import argparse
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", metavar="FILE", help="dataset CSV (.csv or .csv.gz): time_s, gyr_*_rad_s, acc_*_m_s2, ...")
    parser.add_argument("--out", required=True, type=Path, metavar="FILE", help="the recording to write (.gsrec)")


def run(args: argparse.Namespace) -> int:
    import pandas as pd

    from groundstation.datasets import DatasetError, read_csv
    from groundstation.errors import UserError
    from groundstation.export.files import atomic_recording
    from groundstation.recording import EXTENSION

    if args.out.suffix.lower() != EXTENSION:
        raise UserError(f"--out must end in {EXTENSION} (the import writes a recording), not {args.out.name}")
    if args.out.exists():
        raise UserError(f"{args.out} exists; choose another name")
    try:
        read_csv(args.file)  # the same checks and messages as evaluate
    except DatasetError as error:
        raise UserError(str(error)) from None
    frame = pd.read_csv(args.file, compression="infer")
    columns = {name: pd.to_numeric(frame[name], errors="coerce").to_numpy(dtype=float) for name in frame.columns}
    with atomic_recording(args.out, {"source": f"imported from {Path(args.file).name}"}) as writer:
        writer.write_samples(columns)
    print(f"wrote {args.out}: {len(frame)} samples, columns {', '.join(frame.columns)}")
    return 0

"""The BROAD trials the estimator benches score on (``../shared/datasets/broad``), one process per core."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

BROAD = Path(__file__).resolve().parents[1] / ".." / "shared" / "datasets" / "broad"


def per_trial(trial_rows) -> dict | None:
    """``{trial: row}`` from ``trial_rows(path) -> (trial, row)`` over every trial, in two processes;
    None (and a line saying so) when the trials are not there."""
    paths = sorted(BROAD.glob("*.csv*"))
    if not paths:
        print(f"no BROAD trials at {BROAD}")
        return None
    with ProcessPoolExecutor(max_workers=2) as pool:
        return dict(pool.map(trial_rows, paths))

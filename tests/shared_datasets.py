"""The shared datasets beside the repository (``../shared/datasets``: BROAD's trials in ``broad/``, real
flight logs in ``flightlogs/``; README there), and a skip that says which file is absent where."""

from pathlib import Path

import pytest

DATASETS = Path(__file__).resolve().parents[1].parent / "shared" / "datasets"


def shared_dataset(relative: str) -> Path:
    """``DATASETS / relative``, or skip the test with the reason when that file is absent."""
    path = DATASETS / relative
    if not path.exists():
        pytest.skip(f"{relative} is absent from {DATASETS} (the shared datasets beside the repository)")
    return path

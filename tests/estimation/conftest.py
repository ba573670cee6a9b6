"""The BROAD folder beside the repo, for the estimator tests."""

from pathlib import Path

import pytest

BROAD = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "broad"


@pytest.fixture
def broad_dir():
    if not BROAD.is_dir():
        pytest.skip(f"BROAD datasets not found at {BROAD} (expected the shared/ folder beside the repo)")
    return BROAD

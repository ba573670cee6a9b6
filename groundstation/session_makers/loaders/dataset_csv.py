"""A dataset CSV (plain or gzip'd, ``datasets.read_csv``; ../shared/datasets/README.md) read directly."""

from __future__ import annotations

from pathlib import Path

from groundstation.datasets import DatasetError, Trial, read_csv
from groundstation.errors import UserError
from groundstation.session_makers.load import SessionData, from_trial
from groundstation.session_makers.pipeline import DEFAULT_FILTERS
from groundstation.session_makers.replay import check_forced


def load(path, filters=None, forced=None, progress=None) -> SessionData:
    try:
        trial = read_csv(path)
    except DatasetError as error:
        raise UserError(str(error)) from None
    return session_of_trial(trial, filters, forced, {"source": f"dataset CSV {Path(path).name}"})


def session_of_trial(trial: Trial, filters, forced, metadata: dict) -> SessionData:
    """A trial's session with ``filters`` (default: the pipeline's) and the ``forced`` settings: what any
    format of sample columns (a dataset CSV, arrays) gives."""
    filters = DEFAULT_FILTERS if filters is None else filters
    check_forced(filters, forced)
    return from_trial(trial, filters, forced, metadata)

"""The seed papers' experiments, reproduced on the simulator: each module has ``NAME``, ``TITLE`` and
``run(quick: bool) -> report.Result``. ``quick`` shortens the runs (tests); the default is the
papers' durations.
"""

from __future__ import annotations

import importlib

# name -> module; ``groundstation experiments --only NAME`` picks some.
EXPERIMENTS: dict[str, str] = {
    "seed000": "groundstation.experiments.seed000",
    "seed001": "groundstation.experiments.seed001",
    "seed003": "groundstation.experiments.seed003",
    "seed004": "groundstation.experiments.seed004",
    "noise": "groundstation.experiments.noise",
}


def load(name: str):
    return importlib.import_module(EXPERIMENTS[name])

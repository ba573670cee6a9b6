"""Named random streams: every random part of the simulator draws from its own generator.

``stream(seed, name)`` depends only on the seed and the name, never on the order in which parts are
built or on how time is cut into blocks (each stream is consumed in sample order). So the bridge,
stepping every 10 ms, and ``simulate``, stepping in large blocks, produce the same bytes.
"""

from __future__ import annotations

import zlib

import numpy as np


def stream(seed: int, name: str) -> np.random.Generator:
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])

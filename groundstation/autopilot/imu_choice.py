"""Which of an autopilot's IMU streams the estimators run on: the first with real samples, whatever its
message or instance number.

An autopilot names IMUs it does not have: ArduSub sends ``SCALED_IMU2`` all zeros beside its one real
``RAW_IMU``, ArduPilot SITL a zero ``SCALED_IMU3``. A sample is real when it measures gravity: its
acceleration's magnitude within ``REAL_G`` of what a vehicle at rest or hovering reads (1 g), where an
absent sensor reads 0. The first stream to send a real sample is the IMU for the rest of the session,
decided on that sample, so no real sample is lost: the MAVLink front-end (live and ``.tlog``), the
``.tlog`` reader and the DataFlash reader all feed their samples in arrival order through one
``ImuChoice``. (Whether the samples vary is not asked: a simulator's noiseless IMU reads a constant 1 g,
and live the choice cannot wait for a second sample without losing the first.)
"""

from __future__ import annotations

import bisect
import math

REAL_G = (0.5, 2.0)  # |acceleration| of a real sample, g: gravity as a vehicle at rest or hovering reads it


class ImuChoice:
    def __init__(self):
        self.chosen: str | None = None
        self._heard: list[str] = []  # every stream, in the order first heard

    def take(self, source: str, acc_g) -> bool:
        """Whether this sample of stream ``source`` is the estimators' (its stream chosen, now or before)."""
        if source not in self._heard:
            self._heard.append(source)
        if self.chosen is None and REAL_G[0] <= math.hypot(*acc_g) <= REAL_G[1]:
            self.chosen = source
        return source == self.chosen

    @property
    def heard(self) -> bool:
        return bool(self._heard)

    @property
    def passed_over(self) -> list[str]:
        """The streams heard before the choice was made: none of their samples was real."""
        return self._heard[: self._heard.index(self.chosen)] if self.chosen is not None else list(self._heard)

    def said(self) -> str:
        """The choice in words (the Session sheet's "IMU for the estimators", and the warning when a stream was passed over)."""
        if self.chosen is None:
            return f"no IMU stream with real samples (about 1 g): heard {', '.join(self._heard) or 'none'}"
        dead = self.passed_over
        live = [s for s in self._heard if s != self.chosen and s not in dead]
        parts = [f"{self.chosen}, the first with real samples (about 1 g)"]
        if dead:
            parts.append(f"not {', '.join(dead)}: no real samples before it (a sensor the autopilot names but lacks)")
        if live:
            parts.append(f"also {', '.join(live)}, kept as tables of their own")
        return "; ".join(parts)

    def warning(self) -> str | None:
        """What a session warns once the choice is made, when it passed a stream over; else None."""
        return f"IMU for the estimators: {self.said()}" if self.chosen is not None and self.passed_over else None


def said_choice(log, choice: ImuChoice) -> None:
    """A flight log's (``FlightLog``) reader's choice: in its ``imu_choice``, and a warning event at the
    IMU's first sample when a stream was passed over."""
    log.imu_choice = choice.said()
    if log.imu is not None and (warning := choice.warning()):
        bisect.insort(log.events, (int(log.imu.time_us[0]), {"kind": "warning", "message": warning}), key=lambda e: e[0])

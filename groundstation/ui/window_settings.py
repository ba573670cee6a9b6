"""Settings per app window: each window running at once has a settings file of its own (an instance slot).

The first window takes the user's settings ("groundstation"); a second one started while it runs takes
"groundstation-2", and so on, each held by a lock file beside it for as long as the window lives (a crashed
window's lock is taken over: its process is gone). A slot used for the first time starts as a copy of the
first slot's settings. Why slots and not keys merged on write: two windows write the same keys (geometry,
panes, source, Foxglove port), so a merge still lets the last one closed win each of them; with a slot
each, a teacher's two windows on two boards both come back as they were left, and the first window's
settings (the ones a single window uses) are never written by another.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from PySide6 import QtCore

MAX_SLOTS = 16  # windows at once with settings of their own; more share the last slot


@dataclass
class Claim:
    """A slot held: ``slot`` (1 for the first window), released when the window is gone."""

    slot: int
    lock: QtCore.QLockFile | None

    def title(self, base: str) -> str:
        return base if self.slot == 1 else f"{base} (window {self.slot})"

    def release(self) -> None:
        if self.lock is not None:
            self.lock.unlock()


def slot_name(application: str, slot: int) -> str:
    return application if slot == 1 else f"{application}-{slot}"


def window_settings(make: Callable[[str], QtCore.QSettings], application: str = "groundstation") -> tuple[QtCore.QSettings, Claim]:
    """The settings of the first free slot, and the claim on it; ``make(name)``: the settings of that name
    (``QSettings(organization, name)`` in the app)."""
    for slot in range(1, MAX_SLOTS + 1):
        settings = make(slot_name(application, slot))
        path = Path(settings.fileName())
        try:
            path.parent.mkdir(parents=True, exist_ok=True)  # the first start: QSettings makes it only on writing
        except OSError:
            pass  # no lock can be had there: the slots are shared, as before
        lock = QtCore.QLockFile(str(path.with_suffix(".lock")))
        lock.setStaleLockTime(0)  # held while its process lives, however long
        if lock.tryLock(0):
            if slot > 1 and not settings.allKeys():
                first = make(slot_name(application, 1))
                for key in first.allKeys():
                    settings.setValue(key, first.value(key))
            return settings, Claim(slot, lock)
    return settings, Claim(MAX_SLOTS, None)

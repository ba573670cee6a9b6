"""What a new live session takes over from the last one without being asked, said in one line (issue 24,
defect 8): the estimator settings tuned live are stored on disconnect and reused by the next live
session, so a λ set yesterday must not steer today's estimates unseen. No Qt."""

from __future__ import annotations

import dataclasses

from groundstation.estimation import ESTIMATORS, label


def tuned_away(stored: dict[str, dict[str, float]] | None) -> list[str]:
    """"AHF λ min 0.3 rad/s" for each stored setting that differs from the estimator's default."""
    changed = []
    for name, values in (stored or {}).items():
        cls = ESTIMATORS.get(name)
        if cls is None:
            continue
        defaults = dataclasses.asdict(cls.Settings())
        changed += [f"{label(name)} {symbol} {values[setting]:g} {unit}" for setting, symbol, unit in cls.tunable
                    if setting in values and values[setting] != defaults.get(setting)]
    return changed


def carried_over_note(stored: dict[str, dict[str, float]] | None) -> str:
    """The status bar's note on a new live session: '' when it starts from the defaults."""
    changed = tuned_away(stored)
    if not changed:
        return ""
    return f"tuning from the last live session: {', '.join(changed)} (Estimators tab: Defaults to undo)"

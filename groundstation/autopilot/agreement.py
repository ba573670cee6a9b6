"""How closely each host estimator agrees with the autopilot's own attitude estimate.

Not an error: the onboard estimate (ArduPilot's EKF, PX4's EKF2 or attitude estimator) is another
estimate, not truth. Pitch and roll only (ZYX, docs/conventions.md); yaw is left out because the host
filters without a magnetometer start at yaw 0 and drift. Roll differences are wrapped to ±180°.
"""

from __future__ import annotations

import numpy as np

from groundstation import quaternion
from groundstation.estimation.tilt import wrap_pi


def pitch_roll_rad(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    _, pitch, roll = np.moveaxis(quaternion.to_euler_zyx(q), -1, 0)
    return pitch, roll


def agreement(estimates: dict[str, np.ndarray], onboard: np.ndarray) -> dict[str, dict[str, float]]:
    """Per estimator: ``pitch_rms_deg``, ``pitch_max_deg``, ``roll_rms_deg``, ``roll_max_deg`` of the
    difference from ``onboard`` over the rows where both exist, and ``rows`` compared."""
    board_pitch, board_roll = pitch_roll_rad(onboard)
    have = np.isfinite(board_pitch) & np.isfinite(board_roll)
    out = {}
    for name, q in estimates.items():
        pitch, roll = pitch_roll_rad(q)
        keep = have & np.isfinite(pitch) & np.isfinite(roll)
        if not keep.any():
            continue
        d_pitch = np.degrees(np.abs(pitch[keep] - board_pitch[keep]))
        d_roll = np.degrees(np.abs(wrap_pi(roll[keep] - board_roll[keep])))
        out[name] = {
            "pitch_rms_deg": float(np.sqrt(np.mean(d_pitch**2))), "pitch_max_deg": float(d_pitch.max()),
            "roll_rms_deg": float(np.sqrt(np.mean(d_roll**2))), "roll_max_deg": float(d_roll.max()),
            "rows": int(keep.sum()),
        }  # fmt: skip
    return out


def onboard_agreement(data) -> dict[str, dict[str, float]]:
    """``agreement`` of a ``SessionData``'s host estimators with its onboard estimate, on its sample rows."""
    return agreement({name: data.quaternion(name) for name in data.estimated}, data.quaternion("onboard"))

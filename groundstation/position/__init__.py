"""Position and velocity in NED from accelerometer, barometer and GPS (seed 004). No Qt.

Interface::

    acc = linear_acc_ned_m_s2(acc_g, q_body_to_ned)   # body specific force (g) + attitude -> NED m/s²
    f = DualChannel(DualChannelSettings(...))          # or SingleChannel; settings frozen, gains derived
    f.reset()                                          # rest at the origin, nothing seen
    pos_ned_m, vel_ned_m_s = f.step(acc, dt_s, baro_alt_m=None, gps_pos_ned_m=None, gps_vel_ned_m_s=None)
    pos_n3, vel_n3 = f.run(acc_n3, dt_s_n, baro_n, gps_pos_n3, gps_vel_n3)   # NaN rows: no reading

``step`` takes and returns plain floats (tuples), one sample at a time, and costs microseconds; pass a
reading only on the sample it arrived. ``f.bias_ned_m_s2`` is the accelerometer bias estimate.
``complementary`` has the filters and their input guards, ``design`` the gains, ``acceleration`` the
rotation into NED.
"""

from groundstation.position.acceleration import linear_acc_ned_m_s2
from groundstation.position.complementary import (
    DualChannel,
    DualChannelSettings,
    PositionFilter,
    SingleChannel,
    SingleChannelSettings,
)

__all__ = [
    "DualChannel",
    "DualChannelSettings",
    "PositionFilter",
    "SingleChannel",
    "SingleChannelSettings",
    "linear_acc_ned_m_s2",
]

"""Autopilots (ArduPilot, PX4) as sources of sessions: MAVLink messages and flight logs mapped into
this project's units and frames, with no Qt and no session machinery.

- ``records``: what a MAVLink message becomes (IMU sample, onboard attitude, mag, baro, GPS, link
  health, vehicle status, battery, or a generic row of any other message).
- ``mapping.MessageMapper``: one pymavlink message -> records, per-autopilot units, sequence loss counts.
- ``decoder.MavlinkDecoder``: raw link bytes (MAVLink 1 and 2) -> records: ``feed(bytes) -> list``.
- ``streams``: the only uplink we send (stream-rate requests); ``imu_rate``: whether an IMU is fast enough to filter.
- ``tlog``: the standard ``.tlog`` file (8-byte big-endian µs timestamp + raw message).
- ``flightlog``: what a flight log is read into (``FlightLog``: arrays on the autopilot's clock); the
  readers ``tlog``, ``dataflash`` and ``ulog`` fill it.
- ``agreement``: host estimators' pitch/roll difference from the autopilot's own estimate.
- ``messages``: what the autopilot says (texts as ``message`` events, STATUSTEXT chunks joined) and its
  parameters; ``modes``: flight modes by name and ``mode_spans`` (the plots' bands, a report's phases).

What makes a session of them is above, in ``session_makers/``: ``flight_log_session`` (a flight log as a
``SessionData`` with the host estimators run on it) and ``mavlink_front`` (the live pipeline's MAVLink
front-end).

Frames: ArduPilot and PX4 report IMU and attitude on the body axes x forward, y right, z down (FRD)
and attitude body -> NED, which are this project's conventions (docs/conventions.md), so no axis
change is needed; only units change (see ``mapping``).
"""

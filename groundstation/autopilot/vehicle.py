"""Which sender on a MAVLink link is the vehicle, chosen once and never replaced.

The vehicle is the system the user picked (``mavlink:...?system=N``) or else the first autopilot heard:
an ArduPilot or PX4 HEARTBEAT (before any, the first IMU sample or attitude, from the picked system when
there is one). It is one (system, component) pair: a gimbal, camera or companion computer shares the
vehicle's system id but sends its own HEARTBEATs from another component, and so can a spoofer; none of
them is the vehicle. A sender that copies the vehicle's system *and* component cannot be told apart
without MAVLink 2 message signing.

Every other system id heard once a vehicle is chosen is listed in ``others`` (another vehicle, a
radio, a GCS or a spoofer), once.
"""

from __future__ import annotations

from groundstation.autopilot.mapping import MAV_AUTOPILOT_ARDUPILOTMEGA, MAV_AUTOPILOT_PX4
from groundstation.autopilot.records import ImuSample, OnboardAttitude, VehicleStatus

AUTOPILOTS = (MAV_AUTOPILOT_ARDUPILOTMEGA, MAV_AUTOPILOT_PX4)
MIN_SYSTEM, MAX_SYSTEM = 1, 255  # MAVLink system ids (0 is broadcast, never a sender)


class Vehicle:
    def __init__(self, system: int | None = None):
        if system is not None and not MIN_SYSTEM <= system <= MAX_SYSTEM:
            raise ValueError(f"a MAVLink system id is {MIN_SYSTEM} to {MAX_SYSTEM}, not {system}")
        self.picked = system
        self.sender: tuple[int, int] | None = None  # (system, component), once chosen
        self.others: dict[int, int] = {}  # other system id -> the component first heard from it

    def choose(self, record) -> None:
        """An autopilot's HEARTBEAT, an IMU sample or an attitude makes its sender the vehicle when none
        is yet and the user picked its system or none; any other record chooses nothing."""
        if self.sender is None and self.picked in (None, record.system) and chooses(record):
            self.sender = (record.system, record.component)

    def sent(self, record) -> bool:
        return (record.system, record.component) == self.sender

    def newly_other(self, record) -> bool:
        """Whether ``record`` is the first heard from a system other than the vehicle's (listed from now)."""
        vehicle_system = self.sender[0] if self.sender is not None else self.picked
        if vehicle_system is None or record.system == vehicle_system or record.system in self.others:
            return False
        self.others[record.system] = record.component
        return True


def chooses(record) -> bool:
    """Whether ``record`` may make its sender the vehicle: an autopilot's status (not a gimbal's, camera's
    or GCS's), or an IMU sample or attitude before any autopilot's HEARTBEAT."""
    if isinstance(record, VehicleStatus):
        return record.autopilot in AUTOPILOTS
    return isinstance(record, (ImuSample, OnboardAttitude))

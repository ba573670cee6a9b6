"""Firmware + link in simulated time: the bytes a serial port would deliver, and the uplink.

The pty bridge, the in-process port and ``groundstation simulate`` all drive this one object, so
what a recording holds is byte for byte what the bridge would have sent for the same seed.
"""

from __future__ import annotations

import dataclasses

import firmware_protocol as fp
from groundstation.estimation.ahf import AhfSettings
from groundstation.sim.extra_sensors import AuxSettings
from groundstation.sim.firmware import Firmware, FirmwareSettings
from groundstation.sim.imu import MPU6050Settings
from groundstation.sim.link import Chunk, InFlight, Link, LinkSettings
from groundstation.sim.profiles import make_profile


@dataclasses.dataclass(frozen=True)
class Scenario:
    """Everything that decides a simulated session; equal scenarios give identical bytes."""

    profile: str = "flight"
    duration_s: float | None = None  # None: the profile's default
    seed: int = 0
    firmware: FirmwareSettings = FirmwareSettings()
    link: LinkSettings = LinkSettings()
    imu: MPU6050Settings = MPU6050Settings()
    ahf: AhfSettings = AhfSettings()
    extra: AuxSettings = AuxSettings()
    # Who runs the board: "python", the model in firmware.py; "c", the reference firmware's C core
    # (firmware_c.py), the same code as on the STM32.
    firmware_core: str = "python"


class SimStream:
    def __init__(self, scenario: Scenario, on_samples=None):
        self.scenario = scenario
        self.profile = make_profile(scenario.profile, scenario.duration_s, scenario.seed)
        board = Firmware
        if scenario.firmware_core == "c":
            from groundstation.sim.firmware_c import CFirmware as board
        elif scenario.firmware_core != "python":
            raise ValueError(f"firmware_core must be 'python' or 'c', not {scenario.firmware_core!r}")
        self.firmware = board(self.profile, scenario.firmware, scenario.imu, scenario.ahf, scenario.extra, scenario.seed, on_samples)
        self.link = Link(scenario.link, scenario.seed)
        self.uplink = fp.StreamDecoder()
        self._in_flight = InFlight()

    @property
    def end_s(self) -> float:
        """True time at which the profile's duration has been streamed."""
        return self.profile.duration_s

    def advance(self, t_s: float) -> list[Chunk]:
        """Chunks due at the host's port by simulated time ``t_s``, in order."""
        self._in_flight.add(self.link.carry(self.firmware.run_until(t_s)))
        return self._in_flight.due(t_s)

    def flush(self) -> list[Chunk]:
        """The chunks still in flight (for the end of a recording: everything sent arrives)."""
        return self._in_flight.flush()

    def next_event_s(self) -> float:
        """When something next happens: a sample is taken or a chunk falls due."""
        next_sample = self.firmware.true_time_s(self.firmware.next_sample)
        return self._in_flight.next_arrival_s(next_sample)

    def receive(self, data: bytes) -> None:
        """Uplink bytes from the host: COMMAND frames reach the firmware (before its next sample)."""
        for frame in self.uplink.feed(data):
            self.firmware.command(frame)

"""``sim:``: the simulated bridge in process (``SimulatedPort``), paced in real time like a real link.

Every ``bridge-sim`` option is a query parameter under its own name (``sim:?scenario=hover&seed=3&loss=0.05``),
read by the same parser, so the two cannot disagree. Unlike ``bridge-sim`` the default craft carries
every aiding sensor (magnetometer, barometer, GPS: the app's heading and position tabs have something
to show) and flies an hour (``duration=S``); after its profile ends it holds still.
"""

from __future__ import annotations

import argparse

from groundstation.errors import UserError
from groundstation.sources.base import SourceError
from groundstation.sources.serial_port import READ_TIMEOUT_S, PortSource

DEFAULT_DURATION_S = 3600.0
DEFAULT_SENSORS = "mag,baro,gps"


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):
        raise ValueError(message.replace("argument --", "option "))


def parse_scenario(spec):
    """The ``Scenario`` a ``sim:`` spec describes; SourceError naming the bad option."""
    from groundstation.sim.options import add_scenario_arguments, scenario_from_args

    parser = _Parser(prog="sim:", add_help=False)
    add_scenario_arguments(parser)
    parser.set_defaults(sensors=DEFAULT_SENSORS)
    spec.check_options({*vars(parser.parse_args([])), "duration"})
    argv = [f"--{name.replace('_', '-')}={value}" for name, value in spec.options.items() if name != "duration"]
    duration_s = spec.option("duration", float, DEFAULT_DURATION_S)
    try:
        return scenario_from_args(parser.parse_args(argv), duration_s)
    except (ValueError, UserError) as error:
        raise SourceError(f"{spec.text}: {error}") from None


def open_spec(spec) -> PortSource:
    from groundstation.sim.port import SimulatedPort
    from groundstation.sim.stream import SimStream

    scenario = parse_scenario(spec)
    port = SimulatedPort(SimStream(scenario), timeout=READ_TIMEOUT_S)
    return PortSource(port, f"simulated bridge ({scenario.profile}, seed {scenario.seed})")

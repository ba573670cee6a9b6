"""What an autopilot's parameters mean (issue 34: a flyer reads them as Mission Planner and Flight Review show
them): description, units, range, the meaning of the value and the default, non-default ones marked. The
oracles: ArduPilot's documentation as mavio-params gives it (read here through its own API), DFReader's
PARM and pyulog's parameter defaults, mavutil's PARAM_VALUE of the shared tlogs."""

import json
import math

import pytest
from mavio_params import definitions
from pymavlink import DFReader, mavutil
from pyulog import ULog

from groundstation.autopilot.dataflash import read_dataflash
from groundstation.autopilot.parameter_docs import PX4_DOCS_HINT, PX4_FILE, docs_for, non_default
from groundstation.autopilot.ulog import read_ulog
from groundstation.errors import UserError

from mavlink_helpers import flightlog

COPTER = "arducopter_cubeorange_2023-07-06_10-12-18.bin"
HOP = "px4_fmuv5_quad_hop.ulg"


@pytest.fixture(scope="module")
def copter():
    return read_dataflash(flightlog(COPTER))


def parm_records(name: str) -> tuple[dict, dict]:
    """Each parameter's last value and its default where a PARM says it (not NaN), as DFReader reads them."""
    reader, values, defaults = DFReader.DFReader_binary(str(flightlog(name))), {}, {}
    while (msg := reader.recv_match(type="PARM")) is not None:
        values[msg.Name] = msg.Value
        if not math.isnan(getattr(msg, "Default", math.nan)):
            defaults[msg.Name] = msg.Default
    return values, defaults


def test_a_copter_logs_parameters_read_as_ardupilots_copter_documentation_says(copter):
    docs = docs_for(copter.parameters, flightlog(COPTER).parent, copter.parameter_defaults)
    assert "for Copter" in docs.source and docs.described
    documented = definitions("ardupilot.copter")
    described = [name for name in copter.parameters if name in documented]
    # 86 %: the rest are 4.3's names that ArduPilot has since renamed or dropped (SYSID_THISMAV is MAV_SYSID now)
    assert len(described) > 0.8 * len(copter.parameters) and f"{len(described)} of {len(copter.parameters)}" in docs.source
    for name in described:
        entry, doc = documented[name], docs.get(name)
        assert (doc.title, doc.description, doc.units) == (entry["display_name"], entry["description"], entry.get("units", ""))
        if "range" in entry:
            assert (doc.minimum, doc.maximum) == tuple(map(float, entry["range"]))
    gyro = docs.get("INS_GYRO_FILTER")
    assert gyro.units == "Hz" and "gyro" in gyro.description.lower() and gyro.range_text() == "0 .. 256"
    frame = documented["FRAME_CLASS"]["values"]  # an enum: its value's label
    assert docs.get("FRAME_CLASS").meaning(copter.parameters["FRAME_CLASS"]) == frame[int(copter.parameters["FRAME_CLASS"])] == "Quad"
    bits = documented["LOG_BITMASK"]["bitmask"]  # a bitmask: the labels of its set bits, in bit order
    value = int(copter.parameters["LOG_BITMASK"])
    assert docs.get("LOG_BITMASK").meaning(value) == ", ".join(bits[b] for b in sorted(bits) if value >> b & 1)
    assert docs.get("NOT_A_PARAMETER").description == ""


def test_a_dataflash_logs_defaults_are_its_parm_defaults_and_mark_the_non_default_ones(copter):
    values, logged = parm_records(COPTER)
    assert copter.parameter_defaults == logged and len(logged) >= len(values) - 6  # a few with no default known (NaN)
    docs = docs_for(copter.parameters, None, copter.parameter_defaults)
    marked = {name for name, value in copter.parameters.items() if non_default(value, docs.get(name))}
    assert marked == {name for name, value in values.items() if name in logged and value != logged[name]}
    assert len(marked) > 100  # a tuned copter


@pytest.mark.parametrize(("name", "vehicle"), [
    ("arduplane_omnibusf4_ground_pilot_0004.bin", "Plane"), ("ardusub_rov_surface.tlog", "Sub"),
    ("ardurover_boat_sitl_autotest.tlog", "Rover"), ("arduplane_quadplane_sitl.tlog", "Plane"),
])
def test_each_ardupilot_vehicle_is_told_by_its_parameters_names(name, vehicle):
    if name.endswith(".bin"):
        names, defaults = set(parm_records(name)[0]), read_dataflash(flightlog(name)).parameter_defaults
        assert defaults == {}  # ArduPlane 4.2's PARM has no Default: none made up
    else:
        log, names = mavutil.mavlink_connection(str(flightlog(name))), set()
        while (msg := log.recv_match(type="PARAM_VALUE")) is not None:
            names.add(msg.param_id)
    assert len(names) > 80  # the boat's tlog holds 85 (a part of the download), the others all
    assert f"for {vehicle} " in docs_for(names).source


def test_a_px4_log_without_its_metadata_says_where_to_put_it_and_has_its_logged_defaults():
    log = read_ulog(flightlog(HOP))
    ulog = ULog(str(flightlog(HOP)))
    logged = ulog.get_default_parameters(0)  # PX4 logs the system default of each parameter not at it
    assert len(logged) == 80
    assert log.parameter_defaults == {name: float(logged.get(name, value)) for name, value in ulog.initial_parameters.items()}
    docs = docs_for(log.parameters, flightlog(HOP).parent, log.parameter_defaults)
    assert docs.source == PX4_DOCS_HINT and PX4_FILE in docs.source and not docs.described
    assert {name for name, value in log.parameters.items() if non_default(value, docs.get(name))} == set(logged)
    assert read_ulog(flightlog("px4_sitl_quad_groundtruth.ulg")).parameter_defaults == {}  # PX4 1.7 logged none


def test_px4s_parameters_json_beside_the_log_describes_it(tmp_path):
    log = read_ulog(flightlog(HOP))
    (tmp_path / HOP).symlink_to(flightlog(HOP))
    metadata = {"version": 1, "parameters": [
        {"name": "MC_ROLLRATE_P", "type": "Float", "shortDesc": "Roll rate P gain", "longDesc": "Roll rate proportional gain.",
         "min": 0.01, "max": 0.5, "default": 0.15},
        {"name": "BAT1_N_CELLS", "type": "Int32", "shortDesc": "Number of cells", "default": 0,
         "values": [{"value": 0, "description": "Unknown"}, {"value": 4, "description": "4S Battery"}]},
        {"name": "SDLOG_PROFILE", "type": "Int32", "shortDesc": "Logging topic profile", "default": 1,
         "bitmask": [{"index": 0, "description": "Default set"}, {"index": 1, "description": "Estimator replay"}]}]}
    (tmp_path / PX4_FILE).write_text(json.dumps(metadata))
    docs = docs_for(log.parameters, tmp_path, log.parameter_defaults)
    assert str(tmp_path / PX4_FILE) in docs.source and docs.described
    rate = docs.get("MC_ROLLRATE_P")
    assert (rate.title, rate.description, rate.range_text()) == ("Roll rate P gain", "Roll rate P gain. Roll rate proportional gain.", "0.01 .. 0.5")
    assert rate.default == log.parameter_defaults["MC_ROLLRATE_P"]  # the log's own default wins over the file's
    assert docs.get("BAT1_N_CELLS").meaning(log.parameters["BAT1_N_CELLS"]) == "4S Battery"
    assert docs.get("SDLOG_PROFILE").meaning(3) == "Default set, Estimator replay"
    (tmp_path / PX4_FILE).write_text("{not json")
    with pytest.raises(UserError, match=PX4_FILE):
        docs_for(log.parameters, tmp_path)

"""What a QGroundControl or Mission Planner user looks for on a MAVLink link (issue 24): the mode and
arming always in sight, the battery without invented numbers, the GPS fix in MAVLink's words, the
radio's signal as a channel over time. The real window on real UDP (live) or a real .tlog (replay)."""

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from mavlink_helpers import flightlog
from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS


def test_mode_arming_fix_and_rssi_channel_on_a_live_link(qtbot, mavlink_window):
    window = mavlink_window
    badge = window.vehicle_badge
    qtbot.waitUntil(lambda: badge.isVisible(), timeout=LIMIT_MS)
    # The simulated copter's HEARTBEAT: custom mode 0, safety-armed bit clear; pymavlink names the mode.
    assert badge.text() == f"disarmed · {mavutil.mode_mapping_acm[0]}"
    assert badge in window.statusBar().findChildren(type(badge))  # in the status bar: never scrolled away
    view = window.live_view
    view.tabs.setCurrentWidget(view.position)
    fix = view.position.readouts["fix"]
    qtbot.waitUntil(lambda: fix.text() != "—", timeout=LIMIT_MS)
    assert fix.text() == mavlink.enums["GPS_FIX_TYPE"][3].description.split(",")[0]  # the sim reports a 3D fix
    qtbot.waitUntil(lambda: "radio_status.rssi" in {f"{t.name}.{c.name}" for t, c in window.session.view.catalogue.channels()},
                    timeout=LIMIT_MS)
    view.tabs.setCurrentWidget(view.channels)
    view.channels.add("radio_status.rssi")  # the ground radio's signal over time
    curve = next(c for s, c in view.channels.stacked.curves if s.label == "radio_status.rssi")
    qtbot.waitUntil(lambda: curve.yData is not None and len(curve.yData) > 0, timeout=LIMIT_MS)
    from groundstation.sim.mavlink_aircraft import RADIO_STATUS

    assert curve.yData[-1] == RADIO_STATUS["rssi"]


def last_messages(path, types):
    """pymavlink's reading of the log (the oracle): the vehicle's last message of each type."""
    log = mavutil.mavlink_connection(str(path))
    last = {}
    while (msg := log.recv_match(type=list(types))) is not None:
        if msg.get_type() != "HEARTBEAT" or msg.autopilot == mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA:
            last[msg.get_type()] = msg
    return [last[t] for t in types]


def test_a_tlog_says_what_the_autopilot_does_not_measure_and_its_fix_in_mavlinks_words(window, qtbot):
    path = flightlog("arduplane_quadplane_sitl.tlog")
    status, heartbeat, gps = last_messages(path, ("SYS_STATUS", "HEARTBEAT", "GPS_RAW_INT"))
    # SITL without a battery monitor: no current (-1), no remaining (-1), 0 V (no battery powering it reads 0 V)
    assert (status.voltage_battery, status.current_battery, status.battery_remaining) == (0, -1, -1)
    open_file(window, qtbot, path, timeout_ms=120000)
    view = window.live_view
    # a flight log opens whole (issue 34): its Position tab shows once the first refresh has taken the GPS rows
    qtbot.waitUntil(lambda: view.tabs.isTabVisible(view.tabs.indexOf(view.position)), timeout=LIMIT_MS)
    view.tabs.setCurrentWidget(view.position)
    window.tick()  # the whole flight is shown: the panels read its end
    qtbot.waitUntil(lambda: window.link_panel.values["battery"].text() != "—", timeout=LIMIT_MS)
    assert window.link_panel.values["battery"].text() == "not reported"
    armed = bool(heartbeat.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
    expected = f"{'ARMED' if armed else 'disarmed'} · {mavutil.mode_string_v10(heartbeat)}"
    qtbot.waitUntil(lambda: window.vehicle_badge.text() == expected, timeout=LIMIT_MS)  # at its next refresh
    assert gps.fix_type == mavlink.GPS_FIX_TYPE_RTK_FIXED  # type 6, which the window showed as "?"
    qtbot.waitUntil(lambda: view.position.readouts["fix"].text() != "—", timeout=LIMIT_MS)
    assert view.position.readouts["fix"].text() == mavlink.enums["GPS_FIX_TYPE"][gps.fix_type].description.split(",")[0]

"""Flight logs named as a live source (``open_session``: the app's Source box, ``record --port``) get a
message saying how they are opened, whole, not a "damaged recording" error or a traceback; the
window opens them whole (tests/ui/test_replay.py)."""

import pytest

from groundstation.session_makers.factory import open_session
from groundstation.sources import SourceError, whole_file

from mavlink_helpers import flightlog


@pytest.mark.parametrize("spec", ["{}", "mavlink:{}"])
def test_a_tlog_as_a_link_says_it_is_opened_whole(spec):
    path = flightlog("ardurover_boat_sitl_autotest.tlog")
    with pytest.raises(SourceError, match="not a link: open it whole"):
        open_session(spec.format(path))
    assert whole_file(spec.format(path)) == path  # what the window opens instead


@pytest.mark.parametrize("name", ["px4_fmuv5_quad_hop.ulg", "arduplane_omnibusf4_ground_pilot_0004.bin"])
def test_a_flight_log_as_a_link_says_it_is_opened_whole(name):
    with pytest.raises(SourceError, match="flight log, not a link: open it whole"):
        open_session(str(flightlog(name)))
    assert whole_file("udp://127.0.0.1:14550") is None and whole_file("sim:") is None

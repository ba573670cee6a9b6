"""Flight logs named as a live source (the app's Open or Source box) get a message saying what reads
them, not a "damaged recording" error or a traceback."""

import pytest

from groundstation.session.factory import open_session
from groundstation.sources import SourceError

from mavlink_helpers import flightlog


@pytest.mark.parametrize("spec", ["{}", "mavlink:{}"])
def test_a_tlog_in_the_app_says_what_reads_it(spec):
    with pytest.raises(SourceError, match="export and evaluate read"):
        open_session(spec.format(flightlog("ardurover_boat_sitl_autotest.tlog")))


@pytest.mark.parametrize("name", ["px4_fmuv5_quad_hop.ulg", "arduplane_omnibusf4_ground_pilot_0004.bin"])
def test_a_flight_log_says_what_reads_it(name):
    with pytest.raises(SourceError, match="groundstation export and evaluate read it"):
        open_session(str(flightlog(name)))

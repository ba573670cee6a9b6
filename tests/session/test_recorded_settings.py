"""A recording's header holds every live estimator's full settings, NaN and inf included (JSON has
neither: they are written as text); a replay must take them back, whatever they are."""

import numpy as np

from groundstation.recording import RecordingWriter, open_recording
from groundstation.estimation import live_estimators
from groundstation.session.pipeline import Pipeline
from groundstation.session.replay import pipeline_for


def test_the_live_estimators_settings_survive_the_recording_header(tmp_path):
    live = Pipeline(live_estimators())
    path = tmp_path / "live.gsrec"
    with RecordingWriter(path, {"filters": list(live.filters), "estimator_settings": live.settings_json()}):
        pass
    replayed = pipeline_for(open_recording(path))
    assert replayed.filters == live.filters
    np.testing.assert_equal(replayed.settings(), live.settings())  # NaN equals NaN here


def test_a_recording_from_an_older_version_replays_and_says_what_it_left_out(tmp_path):
    """Recordings made before the 3 g accelerometer limit was replaced carry ``acc_max_g``."""
    old = Pipeline(("ahf", "hf")).settings_json()
    old["hf"]["acc_max_g"] = 3.0
    old["hf"]["beta"] = 0.2
    path = tmp_path / "old.gsrec"
    with RecordingWriter(path, {"filters": ["ahf", "hf"], "estimator_settings": old}):
        pass
    replayed = pipeline_for(open_recording(path))
    assert replayed.settings()["hf"]["beta"] == 0.2  # what the old version recorded still applies
    warnings = [e["message"] for e in replayed.events if e["kind"] == "warning"]
    assert len(warnings) == 1 and "hf.acc_max_g" in warnings[0]

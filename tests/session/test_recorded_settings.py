"""A recording's header holds every live estimator's full settings, NaN and inf included (JSON has
neither: they are written as text); a replay must take them back, whatever they are."""

import dataclasses
import math

import numpy as np
import pytest

from groundstation.estimation import ESTIMATORS, live_estimators
from groundstation.recording import RecordingWriter, open_recording
from groundstation.session_makers.pipeline import Pipeline
from groundstation.session_makers.replay import SettingsSchedule, pipeline_for


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


def _away_from_defaults(name: str) -> dict:
    """Every setting of estimator ``name`` changed from its default, each kind a setting has: a boolean
    flipped, a number to infinity ("no limit"), NaN where NaN is its default, any other number halved."""
    defaults = dataclasses.asdict(ESTIMATORS[name].Settings())
    changed = {}
    for key, value in defaults.items():
        if isinstance(value, bool):
            changed[key] = not value
        elif math.isnan(value) or math.isinf(value):
            changed[key] = value
        else:
            changed[key] = math.inf if key.endswith("_max_g") else value / 2
    return changed


@pytest.mark.parametrize("name", list(ESTIMATORS))
def test_every_setting_of_every_estimator_round_trips_without_a_warning(tmp_path, name):
    """Issue 34: booleans, inf and NaN came back as "settings this version cannot read", defaults applied."""
    live = Pipeline((name,))
    tuned = _away_from_defaults(name)
    live.change_settings(name, tuned, 5)
    path = tmp_path / "tuned.gsrec"
    with RecordingWriter(path, {"filters": [name], "estimator_settings": live.settings_json()}) as writer:
        writer.write_event(5, live.events[-1])
    recording = open_recording(path)
    replayed = pipeline_for(recording)
    assert [e["message"] for e in replayed.events if e["kind"] == "warning"] == []
    np.testing.assert_equal(replayed.settings()[name], live.settings()[name])
    schedule = SettingsSchedule(recording)
    schedule.apply_before(replayed, 10)
    np.testing.assert_equal(replayed.settings()[name], {**dataclasses.asdict(ESTIMATORS[name].Settings()), **tuned})


def test_a_warning_about_the_recording_itself_is_dated_at_its_start(tmp_path):
    """Issue 34: the Session sheet dated such a warning at -4376.88 s (host time 0 less the first byte's)."""
    from groundstation.session_makers.load import load_session
    from tests.simulated import simulated_chunks, write_recording

    path = tmp_path / "old.gsrec"
    start_ns = 1_700_000_000_000_000_000  # a host clock far from 0, as a real one is
    write_recording(path, [(start_ns + t, data) for t, data in simulated_chunks(1.0)], {"filters": ["ahf", "gone"]})
    events = load_session(path).events
    warning = next(e for e in events if e["kind"] == "warning" and "gone" in e["message"])
    assert warning["t_s"] == 0.0

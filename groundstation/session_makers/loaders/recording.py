"""The project's recordings (``.gsrec``, docs/recording-format.md): the link's bytes computed again, or an
imported dataset trial's samples."""

from __future__ import annotations

import math

from groundstation.errors import UserError
from groundstation.recording import open_recording
from groundstation.session_makers.load import SessionData, computed, from_pipeline, from_trial, trial_from_samples
from groundstation.session_makers.replay import check_forced, recorded_filters, recorded_settings


def load(path, filters=None, forced=None, progress=None, accept_config_changes: bool = False,
         stream_estimates: bool = False) -> SessionData:
    recording = open_recording(path)
    if recording.chunk_count == 0 and recording.samples:  # an imported dataset; otherwise samples are truth
        trial = trial_from_samples(recording.samples, path)
        filters = recorded_filters(recording)[0] if filters is None else filters
        check_forced(filters, forced)
        settings = {**recorded_settings(recording)}
        for name, values in (forced or {}).items():
            settings[name] = {**settings.get(name, {}), **values}
        origin_s = recording.metadata.get("time_origin_s")
        damage = list(recording.damage)
        if not (isinstance(origin_s, float) and math.isfinite(origin_s)):
            origin_s = None  # recorded by an older import (or its metadata lost): the first row's time
            if damage:
                damage.append("the recording does not say where its time started: session time counts from the "
                              "first intact row, later if rows were lost at the start")
        data = from_trial(trial, filters, settings, recording.metadata, origin_s)
        data.damage = damage
        return data
    if recording.chunk_count == 0:
        raise UserError(f"{path}: the recording holds no data")
    return from_pipeline(recording, computed(recording, filters, forced, progress, accept_config_changes, stream_estimates))

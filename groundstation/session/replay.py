"""Headless replay: a recording through a fresh pipeline, as fast as possible."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from groundstation.errors import UserError
from groundstation.estimation import setting_names
from groundstation.recording import Recording
from groundstation.session.pipeline import DEFAULT_FILTERS, PROTOCOLS, Pipeline


def recorded_settings(recording: Recording) -> dict[str, dict[str, float]]:
    """The estimator settings in the header (``Pipeline.settings_json``), as numbers again; those the
    estimators of this version no longer have (a recording from an older one) are left out and named
    by ``outdated_settings``."""
    recorded = recording.metadata.get("estimator_settings", {})
    return {name: {k: float(v) for k, v in settings.items() if k in setting_names(name)} for name, settings in recorded.items()}


def outdated_settings(recording: Recording) -> list[str]:
    recorded = recording.metadata.get("estimator_settings", {})
    return [f"{name}.{k}" for name, settings in recorded.items() for k in settings if k not in setting_names(name)]


def check_forced(filters, forced) -> None:
    """UserError when ``forced`` (``--set``) names an estimator that does not run: it would be ignored."""
    idle = sorted(set(forced or {}) - set(filters))
    if idle:
        raise UserError(f"--set {', '.join(idle)}: not among the estimators of this session ({', '.join(filters)}); "
                        f"add {' and '.join(idle)} with --filters")


@dataclasses.dataclass(frozen=True)
class RecordedSetup:
    """How a recorded session was set up: its protocol, estimators (and which one aided) and settings, plus ``forced``."""

    filters: tuple[str, ...]
    aiding: str | None  # recorded, if among ``filters``; else the default (``estimation.aiding_estimator``)
    settings: dict[str, dict[str, float]]
    forced: dict | None
    protocol: str
    warnings: list[dict]  # events to start the session's events with


def recorded_setup(recording: Recording, filters=None, forced=None) -> RecordedSetup:
    if filters is None:
        filters = recording.metadata.get("filters", DEFAULT_FILTERS)
    check_forced(filters, forced)
    protocol = recording.metadata.get("protocol", "gs")  # recordings from before MAVLink: the project's frames
    if protocol not in PROTOCOLS:
        raise UserError(f"{recording.path}: recorded from a {protocol!r} link, which this version cannot decode "
                        f"(it knows {', '.join(PROTOCOLS)})")
    warnings = []
    outdated = outdated_settings(recording)
    if outdated:
        warnings.append({"t_host_ns": 0, "kind": "warning", "message": "recorded settings this version's "
                         f"estimators no longer have, left out (their defaults apply): {', '.join(outdated)}"})
    aiding = recording.metadata.get("aiding_estimator")
    return RecordedSetup(tuple(filters), aiding if aiding in filters else None, recorded_settings(recording), forced,
                         protocol, warnings)


def pipeline_for(recording: Recording, filters=None, forced=None) -> Pipeline:
    """A pipeline set up as the recorded session was (protocol, estimators and settings), plus ``forced``."""
    setup = recorded_setup(recording, filters, forced)
    pipeline = Pipeline(setup.filters, setup.settings, forced, protocol=setup.protocol, aiding=setup.aiding)
    pipeline.events += setup.warnings
    return pipeline


def apply_event(pipeline: Pipeline, event: dict) -> None:
    """Re-apply a recorded settings change (other events are informational)."""
    if event.get("kind") == "settings" and event.get("name") in pipeline.estimators:
        pipeline.change_settings(event["name"], event.get("settings", {}), event.get("t_host_ns", 0))


class SettingsSchedule:
    """A recording's settings changes, handed out where they happened in the chunk stream.

    A change recorded at ``t`` applies after every chunk that arrived at or before ``t`` (the live
    session stamps it with the last chunk it had fed), so a replay repeats the live session exactly.
    """

    def __init__(self, recording: Recording):
        self._events = sorted(
            ((t, i, e) for i, (t, e) in enumerate(recording.events) if e.get("kind") == "settings"), key=lambda x: x[:2]
        )
        self._next = 0

    def changes(self) -> list[tuple[float, dict]]:
        """Every recorded change as (t_host_ns, event), in the order they apply."""
        return [(t, e) for t, _, e in self._events]

    def apply_before(self, pipeline: Pipeline, t_host_ns: float) -> None:
        """Apply every change recorded before a chunk that arrived at ``t_host_ns``."""
        while self._next < len(self._events) and self._events[self._next][0] < t_host_ns:
            apply_event(pipeline, self._events[self._next][2])
            self._next += 1


def replay(recording: Recording, filters=None, forced=None, progress: Callable[[int, int], None] | None = None) -> Pipeline:
    """Feed every chunk, re-applying settings changes where they happened; returns the pipeline."""
    pipeline = pipeline_for(recording, filters, forced)
    schedule = SettingsSchedule(recording)
    total = recording.chunk_count
    for i, (t_host_ns, data) in enumerate(recording.chunks()):
        schedule.apply_before(pipeline, t_host_ns)
        pipeline.feed(t_host_ns, data)
        if progress is not None and i % 4096 == 0:
            progress(i, total)
    schedule.apply_before(pipeline, float("inf"))
    if progress is not None:
        progress(total, total)
    return pipeline

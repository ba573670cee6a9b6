"""Headless replay: a recording through a fresh pipeline, as fast as possible."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from groundstation.autopilot.vehicle import MAX_SYSTEM, MIN_SYSTEM
from groundstation.errors import UserError
from groundstation.estimation import ESTIMATORS, settings_from_json
from groundstation.recording import Recording
from groundstation.session_makers.pipeline import DEFAULT_FILTERS, PROTOCOLS, Pipeline


def _header_settings(recording: Recording) -> dict:
    recorded = recording.metadata.get("estimator_settings", {})
    return recorded if isinstance(recorded, dict) else {"estimator_settings": recorded}


def recorded_settings(recording: Recording) -> dict[str, dict[str, float | bool]]:
    """The estimator settings in the header (``Pipeline.settings_json``), each of its type again; those this
    version's estimators do not have or cannot read are left out and named by ``left_out_settings``."""
    return {name: settings_from_json(name, settings)[0] for name, settings in _header_settings(recording).items()
            if name in ESTIMATORS}


def left_out_settings(recording: Recording) -> list[str]:
    """Every recorded setting, in the header or in a settings event, that a replay cannot apply."""
    out = [item for name, settings in _header_settings(recording).items() for item in settings_from_json(str(name), settings)[1]]
    for _, event in recording.events:
        if event.get("kind") == "settings":
            out += settings_from_json(str(event.get("name")), event.get("settings"))[1]
    return list(dict.fromkeys(out))


def recorded_filters(recording: Recording) -> tuple[list[str], list[str]]:
    """The estimators the recorded session ran that this version has; and what the header names that
    cannot run (another version's estimator, or not a list of names)."""
    recorded = recording.metadata.get("filters", DEFAULT_FILTERS)  # JSON gives a list; the default is a tuple
    if not isinstance(recorded, (list, tuple)):
        return list(DEFAULT_FILTERS), [f"filters {recorded!r} (not a list of names)"]
    names = [name for name in recorded if isinstance(name, str) and name in ESTIMATORS]
    return names, [repr(name) for name in recorded if name not in names]


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
    vehicle_system: int | None = None  # MAVLink: the system id the user picked as the vehicle


def recorded_setup(recording: Recording, filters=None, forced=None) -> RecordedSetup:
    warnings = []
    if filters is None:
        filters, unknown = recorded_filters(recording)
        if unknown:
            warnings.append({"t_host_ns": 0, "kind": "warning", "message": "recorded estimators this version does not "
                             f"have, left out: {', '.join(unknown)}"})
    check_forced(filters, forced)
    protocol = recording.metadata.get("protocol", "gs")  # recordings from before MAVLink: the project's frames
    if protocol not in PROTOCOLS:
        raise UserError(f"{recording.path}: recorded from a {protocol!r} link, which this version cannot decode "
                        f"(it knows {', '.join(PROTOCOLS)})")
    left_out = left_out_settings(recording)
    if left_out:
        warnings.append({"t_host_ns": 0, "kind": "warning", "message": "recorded settings this version's "
                         f"estimators do not have or cannot read, left out (their defaults apply): {', '.join(left_out)}"})
    aiding = recording.metadata.get("aiding_estimator")
    vehicle_system = recording.metadata.get("vehicle_system")
    if vehicle_system is not None and not (type(vehicle_system) is int and MIN_SYSTEM <= vehicle_system <= MAX_SYSTEM):
        warnings.append({"t_host_ns": 0, "kind": "warning", "message": f"recorded vehicle_system {vehicle_system!r} is no "
                         "MAVLink system id; the first autopilot heard is the vehicle"})
        vehicle_system = None
    return RecordedSetup(tuple(filters), aiding if aiding in filters else None, recorded_settings(recording), forced,
                         protocol, warnings, vehicle_system)


def pipeline_for(recording: Recording, filters=None, forced=None, accept_config_changes: bool = False,
                 keep_rows: int | None = None) -> Pipeline:
    """A pipeline set up as the recorded session was (protocol, estimators and settings), plus ``forced``;
    ``accept_config_changes``: a CONFIG that changes the scales without a device restart applies (else held);
    ``keep_rows``: tables bounded as a live session's (``Pipeline``)."""
    setup = recorded_setup(recording, filters, forced)
    pipeline = Pipeline(setup.filters, setup.settings, forced, protocol=setup.protocol, aiding=setup.aiding,
                        vehicle_system=setup.vehicle_system, accept_config_changes=accept_config_changes,
                        keep_rows=keep_rows)
    pipeline.events += setup.warnings
    return pipeline


CONFIG_ANSWERS = ("config_accepted", "config_kept")  # the user's answers to a held CONFIG (``ConfigGuard``)


def apply_event(pipeline: Pipeline, event: dict) -> None:
    """Re-apply a recorded settings change or answer to a held CONFIG (other events are informational)."""
    if event.get("kind") == "settings" and event.get("name") in pipeline.estimators:
        pipeline.change_settings(event["name"], event.get("settings", {}), event.get("t_host_ns", 0))
    elif event.get("kind") in CONFIG_ANSWERS:
        pipeline.resolve_config(event["kind"] == CONFIG_ANSWERS[0], event.get("t_host_ns", 0))


class SettingsSchedule:
    """A recording's settings changes (and answers to a held CONFIG), handed out where they happened in the
    chunk stream.

    A change recorded at ``t`` applies after every chunk that arrived at or before ``t`` (the live
    session stamps it with the last chunk it had fed), so a replay repeats the live session exactly.
    """

    def __init__(self, recording: Recording):
        changes = []
        for i, (t, event) in enumerate(recording.events):
            name = event.get("name")
            if event.get("kind") == "settings" and isinstance(name, str):
                kept, _ = settings_from_json(name, event.get("settings"))  # what is left out: left_out_settings
                if kept:
                    changes.append((t, i, {**event, "settings": kept}))
            elif event.get("kind") in CONFIG_ANSWERS:
                changes.append((t, i, event))
        self._events = sorted(changes, key=lambda x: x[:2])
        self._next = 0

    def changes(self) -> list[tuple[float, dict]]:
        """Every recorded change as (t_host_ns, event), in the order they apply."""
        return [(t, e) for t, _, e in self._events]

    def apply_before(self, pipeline: Pipeline, t_host_ns: float) -> None:
        """Apply every change recorded before a chunk that arrived at ``t_host_ns``."""
        while self._next < len(self._events) and self._events[self._next][0] < t_host_ns:
            apply_event(pipeline, self._events[self._next][2])
            self._next += 1


def replay(recording: Recording, filters=None, forced=None, progress: Callable[[int, int], None] | None = None,
           accept_config_changes: bool = False) -> Pipeline:
    """Feed every chunk, re-applying settings changes where they happened; returns the pipeline."""
    pipeline = pipeline_for(recording, filters, forced, accept_config_changes)
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

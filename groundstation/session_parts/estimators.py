"""The host estimators of a session: which, with what settings, and their state.

Settings are kept apart from state: ``recorded`` settings (the session's, changeable while it runs)
and ``forced`` ones (the what-if ``--set`` of replay and export, which win over everything) decide
each estimator's effective settings; the estimator objects hold only state.
"""

from __future__ import annotations

import dataclasses
import math

from groundstation.estimation import about, aiding_estimator, create, settings_as_json
from groundstation.estimation.warm_up import warm_up
from groundstation.estimation.calibration import RestBiasCalibrator

# Every estimator the app runs live is back on truth within this after a restart (``restart``), on a
# reset in flight (tests/session/test_reboot_in_flight.py); the app warns for as long.
RECONVERGE_S = 5.0


class EstimatorBank:
    """``filters``: estimator names; ``aiding``: the one whose attitude the compass heading and the
    position use (``estimation.aiding_estimator``); ``settings``/``forced``: name -> {setting: value}.

    ``compile_in_background`` (a live session): never wait for numba to compile a kernel. An estimator
    whose kernel is not in the cache runs its source interpreted while another process compiles it
    (``estimation.warm_up``), and goes on compiled from the sample after it arrives, its state kept: no
    hole, every row a batch run's within 1e-12 (why, and why not a thread or the install: ``estimation.warm_up``).
    The slow ones (``slow_interpreted``: ukf and sssrukf, 1 ms a sample interpreted where the others take
    0.03-0.15 ms; 100 Hz of both would take a fifth of a core, and a loaded machine's reader fell behind)
    are not run interpreted: their rows are NaN (not computed) until their kernel arrives, compiled last;
    then the samples they missed run through it at once (``_Deferred``), so from there on they are
    what a batch run gives."""

    def __init__(self, filters, settings=None, forced=None, aiding=None, compile_in_background=False):
        self.filters = tuple(dict.fromkeys(filters))
        self.aiding = aiding_estimator(self.filters, aiding)
        self._settings = {name: dict((settings or {}).get(name, {})) for name in self.filters}
        self._forced = {name: dict((forced or {}).get(name, {})) for name in self.filters}
        self._background = compile_in_background
        self.estimators = {name: self._create(name, self._effective(name)) for name in self.filters}
        self._deferred = {name: _Deferred(self.estimators[name]) for name in self.uncompiled() if slow_interpreted(name)}
        self._warm_up, self._seen = None, 0
        if self.uncompiled():
            self._warm_up = warm_up(sorted(self.uncompiled(), key=slow_interpreted))  # the slow ones last
        self.last_q: dict[str, tuple | None] = {name: None for name in self.filters}
        self.at_start = self.settings()
        self.gyro_calibration = RestBiasCalibrator()  # restart() measures again (the user's command)
        self.armed = False  # a MAVLink vehicle's HEARTBEAT says armed: no bias is measured meanwhile
        self._bias_noted: tuple | None = None

    def diagnostics(self) -> dict[str, tuple[str, ...]]:
        """Each estimator's diagnostic outputs, by name (the ``imu`` table's columns after its quaternion)."""
        return {name: est.Diagnostics._fields for name, est in self.estimators.items()}

    def step(self, gyr, acc, dt_s: float, mag, gps) -> list[float]:
        """One sample through every estimator: their quaternions and diagnostics, in order, as one row part.

        Once the craft has been still long enough to measure the gyro bias (``RestBiasCalibrator``), the
        estimators that do not estimate their own get the gyro with that bias removed.
        """
        if self._warm_up is not None and self._warm_up.generation != self._seen:
            self._take_compiled()
        bias = self.gyro_calibration.step(gyr, acc, dt_s, self.armed, mag, gps)
        unbiased = gyr if bias is None else (gyr[0] - bias[0], gyr[1] - bias[1], gyr[2] - bias[2])
        row: list[float] = []
        for name, estimator in self.estimators.items():
            deferred = self._deferred.get(name)
            if deferred is not None:
                row += deferred.missed(gyr if estimator.estimates_gyro_bias else unbiased, acc, dt_s, mag, gps)
                continue
            q, diag = estimator.step(gyr if estimator.estimates_gyro_bias else unbiased, acc, dt_s, mag, gps)
            self.last_q[name] = q
            row += q
            row += diag
        return row

    def uncompiled(self) -> tuple[str, ...]:
        """The estimators whose compiled kernel is not there yet: running interpreted, or (the slow ones) waiting."""
        return tuple(name for name, estimator in self.estimators.items() if estimator.interpreted)

    def _take_compiled(self) -> None:
        """Each estimator whose kernel the other process has put in the cache goes on compiled; a slow one
        first runs the samples it missed. Those it never compiled (it stopped) stay as they are; the
        slow ones forget what they missed."""
        self._seen = self._warm_up.generation
        for name in self._warm_up.compiled & set(self.uncompiled()):
            deferred = self._deferred.get(name)
            if deferred is None:
                self.estimators[name].take_compiled()
            elif (caught_up := deferred.caught_up()) is not None:
                self.estimators[name], self.last_q[name] = caught_up
                del self._deferred[name]
        if self._warm_up.finished:
            self._warm_up = None
            for deferred in self._deferred.values():
                deferred.give_up()

    def _create(self, name: str, settings: dict):
        return create(name, settings, compile=not self._background)

    def new_gyro_bias(self) -> tuple | None:
        """The gyro bias (rad/s) once, just after it was measured; None otherwise."""
        bias = self.gyro_calibration.bias_rad_s
        if bias is None or bias == self._bias_noted:
            return None
        self._bias_noted = bias
        return bias

    def aiding_q(self):
        """The newest attitude of the aiding estimator (the compass and the position use it), or None."""
        return self.last_q[self.aiding] if self.aiding else None

    def restart(self) -> None:
        """After a device reset or clock jump: every estimator starts over from its last attitude.

        The board's reset restarts its gyro calibration, not the craft: what each estimator learnt of
        the sensors (its gyro bias above all: the board may now subtract another offset) is forgotten,
        so a new bias is learnt from zero, but the attitude is kept. Started from gravity instead, in
        flight the tilt would come from an accelerating accelerometer and the heading from nothing
        (0, or the compass only for a filter whose first sample has a reading): a magnetometer filter
        took minutes to turn 100 degrees back (tests/session/test_reboot_in_flight.py).
        """
        for name, estimator in self.estimators.items():
            if name in self._deferred:
                self._deferred[name].missed_event(_RESTART)
            else:
                estimator.restart(q0=self.last_q[name])

    def change(self, name: str, overrides: dict[str, float]) -> None:
        """New settings for one estimator from now on, keeping its attitude; ValueError before any change."""
        if name not in self.estimators:
            raise ValueError(f"{name} is not among this session's estimators ({', '.join(self.filters)})")
        estimator = self._create(name, {**self._settings[name], **overrides, **self._forced[name]})  # validates first
        self._settings[name].update(overrides)
        if name in self._deferred:
            self._deferred[name].missed_event(estimator)
        elif self.last_q[name] is not None:
            estimator.reset(q0=self.last_q[name])
        self.estimators[name] = estimator

    def settings(self) -> dict[str, dict[str, float]]:
        """Every estimator's full settings as in effect now."""
        return {name: dataclasses.asdict(est.settings) for name, est in self.estimators.items()}

    def settings_json(self) -> dict[str, dict[str, float | bool | str]]:
        """``settings()`` for a JSON file (``settings_as_json``)."""
        return {name: settings_as_json(settings) for name, settings in self.settings().items()}

    def _effective(self, name: str) -> dict[str, float]:
        return {**self._settings[name], **self._forced[name]}


def slow_interpreted(name: str) -> bool:
    """The GPS-aided unscented filters (ukf, sssrukf): about 1 ms a sample interpreted, 10-30 times the others
    (``EstimatorBank``)."""
    return "gps" in about(name).needs


_RESTART = "restart"  # in a ``_Deferred`` backlog: the bank restarted its estimators there


class _Deferred:
    """A slow estimator waiting for its compiled kernel: what it missed (samples, restarts, settings
    changes: the new estimator) in order, run through it once the kernel is there."""

    def __init__(self, estimator):
        self.estimator = estimator  # as the session made it
        self.backlog: list | None = []  # None: its kernel will not come in this session, nothing is kept
        self._blank = [math.nan] * (4 + len(estimator.Diagnostics._fields))

    def missed(self, *sample) -> list[float]:
        """A sample kept for later; its row part NaN (not computed)."""
        if self.backlog is not None:
            self.backlog.append(sample)
        return self._blank

    def missed_event(self, event) -> None:
        """A restart (``_RESTART``) or new settings (the estimator made with them), kept for later."""
        if self.backlog is not None:
            self.backlog.append(event)

    def give_up(self) -> None:
        """The compiling process ended without this kernel (it failed): NaN for the rest of the session,
        with nothing kept that nobody will run."""
        self.backlog = None

    def caught_up(self):
        """``(estimator, its last q)`` after the samples it missed, compiled; None while the kernel is not there."""
        if not self.estimator.take_compiled():
            return None
        estimator, q = self.estimator, None
        for item in self.backlog:
            if item is _RESTART:
                estimator.restart(q0=q)
            elif isinstance(item, tuple):
                q, _ = estimator.step(*item)
            else:  # new settings from here on, the attitude kept (``EstimatorBank.change``)
                item.take_compiled()
                if q is not None:
                    item.reset(q0=q)
                estimator = item
        return estimator, q

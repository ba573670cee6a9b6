"""A one-line progress bar with ETA on stderr, for anything that takes more than a second; the line said
before a command's first compile of its estimators (``say_compiling``)."""

from __future__ import annotations

import sys
import time

from groundstation.text import clean


SHOW_AFTER_S = 1.0  # a job that ends sooner shows no bar


class ProgressBar:
    WIDTH = 30

    def __init__(self, label: str, stream=None, delay_s: float | None = None):
        self.label = clean(label, visible=True)  # a file's name: shown, never acting on the terminal
        self.stream = stream or sys.stderr  # looked up now: tests may have replaced it
        self._start = time.monotonic()
        self._delay_s = SHOW_AFTER_S if delay_s is None else delay_s
        self._shown = False
        self._drawn = ""

    def __call__(self, done: float, total: float) -> None:
        elapsed = time.monotonic() - self._start
        if elapsed < self._delay_s or total <= 0:
            return
        fraction = min(done / total, 1.0)
        eta = elapsed * (1 - fraction) / fraction if fraction > 0 else float("nan")
        bar = "#" * int(fraction * self.WIDTH)
        text = f"\r{self.label} [{bar:<{self.WIDTH}}] {fraction:4.0%} ETA {eta:4.0f} s"
        if text == self._drawn:  # a reader may report many times a percent: the terminal gets each change once
            return
        self._drawn = text
        self.stream.write(text)
        self.stream.flush()
        self._shown = True

    def done(self) -> None:
        if self._shown:
            self.stream.write("\n")
            self.stream.flush()


class StagedProgress:
    """``progress(stage, done, total)``: one bar per stage ("decoding", then "writing")."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stderr  # looked up now: tests and callers may have replaced it
        self.stage: str | None = None
        self.bar: ProgressBar | None = None

    def __call__(self, stage: str, done: float, total: float) -> None:
        if stage != self.stage:
            self.done()
            self.stage, self.bar = stage, ProgressBar(stage, self.stream)
        self.bar(done, total)

    def done(self) -> None:
        if self.bar is not None:
            self.bar.done()
            self.bar = None


def say_compiling(path, filters, stream=None) -> None:
    """One line on stderr when the estimators a command runs on ``path`` compile first (numba's cache empty, as
    after an install): once per machine, seconds each, so that nobody takes the wait for a hang. Compiling in
    parallel processes would not save CPU, nor the wall time of a machine already busy
    (bench/bench_first_data.out.md)."""
    from groundstation.errors import UserError
    from groundstation.session_makers.load import not_compiled, planned_estimators

    try:
        waiting = not_compiled(planned_estimators(path, filters))
    except (UserError, OSError, ValueError):
        return  # the load says what is wrong with the file
    if waiting:
        print(f"compiling {len(waiting)} estimator{'s' if len(waiting) > 1 else ''} for this machine, once (2-10 CPU s "
              "each; later runs start at once)…", file=stream or sys.stderr, flush=True)

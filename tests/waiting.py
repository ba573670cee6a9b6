"""Waiting in tests of real processes, ports and threads: poll until the condition holds, with a timeout
generous enough for a loaded 2-core machine (other test processes, a compiler), never for a fixed time."""

import time

# How long a wait for a condition may take before the test fails: only a broken product should reach it.
# Beside CPU hogs at load 20-30 on 2 cores, steps that take a second at rest took 20-25 s, so the limit
# is minutes; a condition that holds returns at once, so a generous limit costs a passing test nothing.
LIMIT_S = 120.0
LIMIT_MS = round(LIMIT_S * 1000)  # for qtbot.waitUntil


def wait_for(condition, timeout_s: float = LIMIT_S, what: str = "the condition") -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, f"{what}: not within {timeout_s:g} s"
        time.sleep(0.05)

"""Waiting in tests of real processes, ports and threads: poll until the condition holds, with a timeout
generous enough for a loaded 2-core machine (other test processes, a compiler), never for a fixed time."""

import time


def wait_for(condition, timeout_s: float = 30.0, what: str = "the condition") -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, f"{what}: not within {timeout_s:g} s"
        time.sleep(0.05)

"""A kill closes the window once the code it interrupts is done, never inside it (issue 35: a SIGTERM
handled while the redraw held the session's lock closed the window there, and the close waited for the
reader thread, which waited for that lock)."""

import signal
import threading

from groundstation.ui.app import close_on_signals
from tests.waiting import LIMIT_MS


def test_a_kill_closes_the_window_after_the_code_it_interrupted(window, qtbot):
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        close_on_signals(window)
        with threading.Lock():  # as the redraw holds the session's lock
            signal.raise_signal(signal.SIGTERM)
            assert window.isVisible()  # not closed in here
        qtbot.waitUntil(lambda: not window.isVisible(), timeout=LIMIT_MS)
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)

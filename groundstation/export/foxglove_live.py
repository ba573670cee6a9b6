"""A live session served to Foxglove (and Lichtblick, and any client of the Foxglove WebSocket protocol).

``FoxgloveBridge(host, port).serve(session)`` starts foxglove-sdk's WebSocket server and, on a thread of its
own, every ``PERIOD_S``, logs the rows the session's tables gained since the last time: the same topics
as an MCAP export (``foxglove_topics.Topics``), so a flight watched live and its file later look alike.
It listens on 127.0.0.1 unless told otherwise: the session is the user's, not the network's.
"""

from __future__ import annotations

import threading
import time

from groundstation.errors import UserError
from groundstation.export.foxglove_topics import Topics
from groundstation.session.view import Session, event_session_time_s

PERIOD_S = 0.05  # 20 batches a second: a Foxglove plot looks live, and each batch is a few rows of each table
BACKLOG_MESSAGES = 65_536  # per client: several seconds of every topic, so a slow client loses nothing


def parse_address(text: str, default_host: str = "127.0.0.1") -> tuple[str, int]:
    """``[HOST:]PORT`` as (host, port); UserError for anything else."""
    host, _, port = text.rpartition(":")
    try:
        number = int(port)
    except ValueError:
        number = -1
    if not 0 <= number <= 65535:
        raise UserError(f"--foxglove {text}: give [HOST:]PORT, a port from 0 to 65535 (0: any free port)")
    return host.strip("[]") or default_host, number


class FoxgloveBridge:
    """A Foxglove WebSocket server on ``host:port`` (UserError when it cannot listen there); ``serve(session)``
    (a ``view.Session``) before the session starts serves every row from the first; ``close()`` stops it."""

    def __init__(self, host: str = "127.0.0.1", port: int = 8765):
        import foxglove

        self._context = foxglove.Context()
        try:
            self._server = foxglove.start_server(name="groundstation", host=host, port=port, context=self._context,
                                                 message_backlog_size=BACKLOG_MESSAGES)
        except Exception as error:  # foxglove raises RuntimeError with the OS's reason (address in use, ...)
            raise UserError(f"cannot serve Foxglove on {host}:{port}: {error}") from None
        self.host = host
        self.session: Session | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="groundstation-foxglove", daemon=True)

    def serve(self, session: Session, history: bool = True) -> FoxgloveBridge:
        """Serves ``session``; ``history``: also the rows it has already (False: from now on, as when a
        switch is turned on during a flight, whose past no client connected now would receive)."""
        view = session.view
        self.session = session
        # Session time 0 on the wall clock: set from the first chunk's arrival once there is one.
        self._topics = Topics(self._context, view.catalogue, time.time_ns())
        self._topics.advertise(view.tables)
        with session.lock:
            self._sent_rows = {} if history else {name: len(table) for name, table in view.tables.items()}
            self._sent_events = 0 if history else len(view.events)
        self._origin_set = False
        self._thread.start()
        return self

    @property
    def port(self) -> int:
        return self._server.port

    @property
    def address(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def _run(self) -> None:
        while not self._stop.wait(PERIOD_S):
            self.pump()

    def pump(self) -> None:
        """Logs what the session gained since the last call."""
        view = self.session.view
        with self.session.lock:
            if not self._origin_set and view.t0_host_ns is not None:
                self._topics.origin = time.time_ns() - (time.monotonic_ns() - view.t0_host_ns)
                self._origin_set = True
            self._topics.catalogue = view.catalogue  # a MAVLink session adds tables as their messages come
            batches = []
            for name, table in list(view.tables.items()):
                new = len(table) - self._sent_rows.get(name, 0)
                if new > 0:
                    batches.append((name, table.columns, table.tail(new)))
                    self._sent_rows[name] = len(table)
            events = view.events[self._sent_events:]
            self._sent_events += len(events)
            times = [event_session_time_s(view, e) for e in events]
        for name, columns, rows in batches:  # logged outside the lock: the reader thread goes on
            self._topics.rows(name, {c: rows[:, i] for i, c in enumerate(columns)})
        self._topics.events(events, times)

    def close(self) -> None:
        """Sends what is left, then stops the server."""
        self._stop.set()
        if self.session is not None:
            self._thread.join(timeout=5)
            self.pump()
        self._server.stop()

"""A live session served to Foxglove (and Lichtblick, and any client of the Foxglove WebSocket protocol).

``FoxgloveBridge(host, port).serve(session)`` listens for Foxglove clients and, on a thread of its own,
every ``PERIOD_S``, logs the rows the session's tables gained since the last time: the same topics as an
MCAP export (``foxglove_topics.Topics``), so a flight watched live and its file later look alike.
It listens on 127.0.0.1 unless told otherwise: the session is the user's, not the network's.

Who is served:
- either name of the protocol (``SUBPROTOCOLS``): ``foxglove.sdk.v1``, which Foxglove's apps and SDK offer
  now, and ``foxglove.websocket.v1``, the same protocol under its older name, which Foxglove's npm client
  ``@foxglove/ws-protocol`` and Lichtblick before 1.22 offer;
- a native app (no ``Origin`` header); a web page only from this machine (``localhost``, 127.0.0.1,
  [::1]) or from Foxglove's or Lichtblick's web app (``WEB_APP_ORIGINS``), and only while ``web_apps``
  is on; any other page is refused with HTTP 403, so a site the user happens to visit cannot read the flight;
- at most ``max_clients`` at once: one more is told why in a status message and closed (code 1013,
  "try again later").

Each client has a queue of ``queue_bytes``: a client that reads slower than the session sends loses the
oldest messages, not the server's memory; the drops are counted (``dropped``, ``status_text``) and the
client is told in a status message.

Why not foxglove-sdk's own server (``foxglove.start_server``, 0.30): it gives no hook on the handshake.
It accepts only ``foxglove.sdk.v1`` (HTTP 400 to the npm client), any Origin and any number of clients,
each with a backlog counted in messages (18-20 MB for a client that stops reading, kept after it leaves).
Fronting it with a proxy that checks would leave its own port open on 127.0.0.1 to any page that finds
it. So the server side of the protocol (serverInfo, advertise, status, message data; subscribe and
unsubscribe from the client) is served here with ``websockets``, while the SDK keeps doing what it does
well: the topics are still logged into a foxglove ``Context`` (``Topics``, the same code as the MCAP
file). Its channels are announced to this server as the context opens them (the ``channel_filter`` of
an MCAP writer on the context, which sees each channel's descriptor), and their messages arrive as the
records of that writer's unchunked stream (``McapTap``): a client receives, byte for byte, the messages
a file would hold.
"""

from __future__ import annotations

import asyncio
import base64
import collections
import errno
import json
import struct
import threading
import time
import urllib.parse
from http import HTTPStatus

from groundstation.errors import UserError
from groundstation.export.foxglove_topics import Topics
from groundstation.session.view import Session, event_session_time_s

PERIOD_S = 0.05  # 20 batches a second: a Foxglove plot looks live, and each batch is a few rows of each table
SUBPROTOCOLS = ("foxglove.sdk.v1", "foxglove.websocket.v1")  # one protocol under its new and its old name
# The web apps of Foxglove and of Lichtblick (its build on GitHub Pages): pages that may connect while
# ``web_apps`` is on, besides the pages of this machine.
WEB_APP_ORIGINS = frozenset({"https://app.foxglove.dev", "https://lichtblick-suite.github.io"})
LOCAL_HOSTS = frozenset({"localhost", "127.0.0.1", "::1"})
MAX_CLIENTS = 16
# Per client, besides the kernel's socket buffers (which fill first): about 1 s of every topic of a 100 Hz
# session; a client further behind loses the oldest.
QUEUE_BYTES = 1 << 19
DROP_NOTICE_S = 5.0  # a client that drops is told at most this often
CLOSE_STALL_S = 2.0  # close() waits for a client's queue to empty while the client goes on reading

MESSAGE_DATA = 0x01  # the protocol's server binary opcode: u8 opcode, u32 subscription id, u64 log time ns, payload
_MESSAGE_HEADER = struct.Struct("<BIQ")
_STATUS_WARNING, _STATUS_ERROR = 1, 2  # the protocol's status levels (0 is info)


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


def origin_allowed(origin: str | None, web_apps: bool) -> bool:
    """Whether a connection whose ``Origin`` header is ``origin`` is served: always without one (a native
    app sends none; a browser always does); a page of this machine or of Foxglove's or Lichtblick's web
    app only while ``web_apps`` is on; any other page never."""
    if origin is None:
        return True
    if not web_apps:
        return False
    if origin in WEB_APP_ORIGINS:
        return True
    parts = urllib.parse.urlsplit(origin)
    return parts.scheme in ("http", "https") and parts.hostname in LOCAL_HOSTS


class McapTap:
    """The file-like end of an unchunked MCAP stream (``foxglove.open_mcap`` on it): keeps what the writer
    writes, and ``records()`` hands over the whole records written so far, as (opcode, body)."""

    MAGIC = b"\x89MCAP0\r\n"
    CHANNEL, MESSAGE = 0x04, 0x05

    def __init__(self):
        self._buffer = bytearray()
        self._position = 0
        self._magic_left = len(self.MAGIC)

    def write(self, data) -> int:
        self._buffer += data
        self._position += len(data)
        return len(data)

    def seek(self, offset: int, whence: int = 0) -> int:  # the writer is told not to seek: it only asks where it is
        return self._position

    def tell(self) -> int:
        return self._position

    def flush(self) -> None:
        pass

    def records(self) -> list[tuple[int, memoryview]]:
        skip = min(self._magic_left, len(self._buffer))
        self._magic_left -= skip
        data = bytes(self._buffer)
        out, at = [], skip
        while at + 9 <= len(data):
            opcode, length = data[at], int.from_bytes(data[at + 1:at + 9], "little")
            if at + 9 + length > len(data):
                break
            out.append((opcode, memoryview(data)[at + 9:at + 9 + length]))
            at += 9 + length
        del self._buffer[:at]
        return out


def _mcap_topic(body: memoryview) -> tuple[int, str]:
    """An MCAP Channel record's id and topic."""
    length = int.from_bytes(body[4:8], "little")
    return int.from_bytes(body[:2], "little"), bytes(body[8:8 + length]).decode()


def advertised_channel(descriptor) -> dict:
    """A foxglove ``ChannelDescriptor`` as the protocol advertises it (a binary schema in base64, as it asks)."""
    schema = descriptor.schema
    name, encoding, data = (schema.name, schema.encoding, bytes(schema.data)) if schema is not None else ("", "", b"")
    text = data.decode() if encoding in ("jsonschema", "ros1msg", "ros2msg") else base64.b64encode(data).decode()
    return {"id": descriptor.id, "topic": descriptor.topic, "encoding": descriptor.message_encoding,
            "schemaName": name, "schema": text, **({"schemaEncoding": encoding} if encoding else {})}


class _Client:
    """One connection: its subscriptions (channel id -> subscription id) and what waits to be sent to it."""

    def __init__(self, websocket, queue_bytes: int):
        self.websocket = websocket
        self.subscriptions: dict[int, int] = {}
        self.control: collections.deque[str] = collections.deque()  # never dropped: few and small
        # (subscription id, log time ns, payload): the payload is shared by every client (10 clients that
        # stop reading hold one copy of the latest messages, not ten); the frame is made as it is sent.
        self.data: collections.deque[tuple[int, int, bytes]] = collections.deque()
        self.queued_bytes = 0
        self.queue_bytes = queue_bytes
        self.dropped = 0
        self.told_dropped = 0
        self.told_at = -DROP_NOTICE_S
        self.wake = asyncio.Event()

    def push(self, subscription: int, log_time: int, payload: bytes) -> int:
        """Queues a message; returns how many of the oldest were dropped to keep the queue within its size."""
        self.data.append((subscription, log_time, payload))
        self.queued_bytes += _MESSAGE_HEADER.size + len(payload)
        dropped = 0
        while self.queued_bytes > self.queue_bytes and len(self.data) > 1:
            self.queued_bytes -= _MESSAGE_HEADER.size + len(self.data.popleft()[2])
            dropped += 1
        self.dropped += dropped
        return dropped


class PortTaken(UserError):
    """The port is served already (another window or session, another program): the caller may try the next."""


class FoxgloveBridge:
    """A Foxglove WebSocket server on ``host:port`` (UserError when it cannot listen there); ``serve(session)``
    (a ``view.Session``) before the session starts serves every row from the first; ``close()`` stops it.
    ``web_apps``: serve web pages of this machine and Foxglove's and Lichtblick's web apps (native apps
    always); ``max_clients`` and ``queue_bytes``: see the module's notes."""

    def __init__(self, host: str = "127.0.0.1", port: int = 8765, *, web_apps: bool = True,
                 max_clients: int = MAX_CLIENTS, queue_bytes: int = QUEUE_BYTES):
        import foxglove
        from foxglove.mcap import MCAPWriteOptions

        self.host = host
        self.web_apps = web_apps
        self.max_clients = max_clients
        self.queue_bytes = queue_bytes
        self.dropped = 0  # messages dropped for clients slower than the session, since the start
        self.refused = 0  # connections refused: a foreign Origin, or one client too many
        self._clients: set[_Client] = set()
        self._channels: dict[int, dict] = {}  # advertised so far (the server's thread only)
        self._loop = asyncio.new_event_loop()
        self._loop_thread = threading.Thread(target=self._loop.run_forever, name="groundstation-foxglove-server",
                                             daemon=True)
        self._loop_thread.start()
        try:
            self._server = asyncio.run_coroutine_threadsafe(self._listen(host, port), self._loop).result()
        except OSError as error:  # the address is in use, or not this machine's, or the host is unknown
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._loop_thread.join()
            self._loop.close()
            taken = PortTaken if error.errno == errno.EADDRINUSE else UserError
            raise taken(f"cannot serve Foxglove on {host}:{port}: {error.strerror or error}") from None
        self.port: int = self._server.sockets[0].getsockname()[1]  # the one chosen when asked for port 0
        self._context = foxglove.Context()
        self._tap = McapTap()
        self._ids: dict[str, int] = {}  # topic -> the context's channel id (the pump's thread)
        self._mcap_ids: dict[int, int] = {}  # the tap's channel id -> the context's
        self._writer = foxglove.open_mcap(self._tap, context=self._context, channel_filter=self._opened,
                                          writer_options=MCAPWriteOptions(
            use_chunks=False, compression=None, disable_seeking=True, emit_statistics=False,
            emit_summary_offsets=False, emit_message_indexes=False, emit_chunk_indexes=False, repeat_channels=False,
            repeat_schemas=False, calculate_data_section_crc=False, calculate_summary_section_crc=False))
        self.session: Session | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="groundstation-foxglove", daemon=True)

    def _opened(self, descriptor) -> bool:
        """The context opened a channel (foxglove calls this then): it is advertised at once."""
        self._ids[descriptor.topic] = descriptor.id
        self._loop.call_soon_threadsafe(self._publish, [advertised_channel(descriptor)], [])
        return True

    async def _listen(self, host: str, port: int):
        from websockets.asyncio.server import serve

        # No compression: it would cost each client a zlib context and the 2-core machine a deflate per message.
        return await serve(self._connection, host, port, subprotocols=list(SUBPROTOCOLS), compression=None,
                           process_request=self._check_origin, close_timeout=CLOSE_STALL_S,
                           server_header="groundstation")

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
    def address(self) -> str:
        return f"ws://{self.host}:{self.port}"

    @property
    def clients(self) -> int:
        return len(self._clients)

    def queues(self) -> list[tuple[int, int]]:
        """(bytes queued, messages dropped) of each client connected now."""

        async def read():
            return [(client.queued_bytes, client.dropped) for client in self._clients]

        return asyncio.run_coroutine_threadsafe(read(), self._loop).result()

    def status_text(self) -> str:
        """What the status bar and ``record`` say: the address, the clients, the drops."""
        text = f"Foxglove: {self.address}, {self.clients} client{'' if self.clients == 1 else 's'}"
        return text + (f", {self.dropped} messages dropped for slow clients" if self.dropped else "")

    def _run(self) -> None:
        while not self._stop.wait(PERIOD_S):
            self.pump()

    def pump(self) -> None:
        """Logs what the session gained since the last call, and hands it to the clients."""
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
        self._writer.flush()
        messages = []
        for opcode, body in self._tap.records():
            if opcode == McapTap.MESSAGE:  # u16 channel, u32 sequence, u64 log time, u64 publish time, data
                messages.append((self._mcap_ids[int.from_bytes(body[:2], "little")],
                                 int.from_bytes(body[6:14], "little"), bytes(body[22:])))
            elif opcode == McapTap.CHANNEL:  # the file numbers its channels in their order of first message
                mcap_id, topic = _mcap_topic(body)
                self._mcap_ids[mcap_id] = self._ids[topic]
        if messages:
            self._loop.call_soon_threadsafe(self._publish, [], messages)

    # --- the server's thread (asyncio) ---

    def _check_origin(self, connection, request):
        origin = request.headers.get("Origin")
        if origin_allowed(origin, self.web_apps):
            return None
        self.refused += 1
        allowed = "native apps, pages of this machine, Foxglove's and Lichtblick's web apps" if self.web_apps else "native apps"
        return connection.respond(HTTPStatus.FORBIDDEN, f"groundstation serves its live session to {allowed}; "
                                                        f"not to a page of {origin}\n")

    async def _connection(self, websocket) -> None:
        from websockets.exceptions import ConnectionClosed

        if len(self._clients) >= self.max_clients:
            self.refused += 1
            message = (f"groundstation serves at most {self.max_clients} Foxglove clients at once and has "
                       f"{len(self._clients)}: close one and connect again")
            try:
                await websocket.send(json.dumps({"op": "status", "level": _STATUS_ERROR, "message": message}))
                await websocket.close(1013, f"at most {self.max_clients} clients at once")
            except ConnectionClosed:
                pass
            return
        client = _Client(websocket, self.queue_bytes)
        self._clients.add(client)
        client.control.append(json.dumps({"op": "serverInfo", "name": "groundstation", "capabilities": [],
                                          "metadata": {}, "sessionId": str(id(self))}))
        if self._channels:
            client.control.append(json.dumps({"op": "advertise", "channels": list(self._channels.values())}))
        client.wake.set()
        sender = asyncio.create_task(self._send(client))
        try:
            async for message in websocket:
                if isinstance(message, str):
                    self._request(client, message)
        except ConnectionClosed:
            pass
        finally:
            self._clients.discard(client)
            sender.cancel()
            client.data.clear()

    async def _send(self, client: _Client) -> None:
        from websockets.exceptions import ConnectionClosed

        try:
            while True:
                await client.wake.wait()
                client.wake.clear()
                while client.control or client.data:
                    if client.control:
                        frame = client.control.popleft()
                    else:
                        subscription, log_time, payload = client.data.popleft()
                        client.queued_bytes -= _MESSAGE_HEADER.size + len(payload)
                        frame = _MESSAGE_HEADER.pack(MESSAGE_DATA, subscription, log_time) + payload
                    await client.websocket.send(frame)
        except ConnectionClosed:
            pass

    def _request(self, client: _Client, text: str) -> None:
        """A client's subscribe or unsubscribe; anything else (this server offers no other capability) is said."""
        try:
            message = json.loads(text)
            if message.get("op") == "subscribe":
                for subscription in message["subscriptions"]:
                    client.subscriptions[int(subscription["channelId"])] = int(subscription["id"])
                return
            if message.get("op") == "unsubscribe":
                gone = {int(i) for i in message["subscriptionIds"]}
                client.subscriptions = {c: s for c, s in client.subscriptions.items() if s not in gone}
                return
            problem = f"groundstation's Foxglove server does not handle op {message.get('op')!r}"
        except (ValueError, TypeError, KeyError, AttributeError) as error:
            problem = f"groundstation's Foxglove server could not read a request: {error}"
        client.control.append(json.dumps({"op": "status", "level": _STATUS_WARNING, "message": problem}))
        client.wake.set()

    def _publish(self, advertised: list[dict], messages: list[tuple[int, int, bytes]]) -> None:
        if advertised:
            self._channels.update((c["id"], c) for c in advertised)
            text = json.dumps({"op": "advertise", "channels": advertised})
            for client in self._clients:
                client.control.append(text)
        now = time.monotonic()
        for client in self._clients:
            subscriptions = client.subscriptions
            for channel_id, log_time, payload in messages:
                subscription = subscriptions.get(channel_id)
                if subscription is not None:
                    self.dropped += client.push(subscription, log_time, payload)
            if client.dropped > client.told_dropped and now - client.told_at >= DROP_NOTICE_S:
                client.control.append(json.dumps({"op": "status", "level": _STATUS_WARNING, "message": (
                    f"groundstation dropped {client.dropped} messages for this connection: it reads slower than "
                    f"the live session sends, and its queue holds {self.queue_bytes / 2**20:g} MiB")}))
                client.told_dropped, client.told_at = client.dropped, now
            client.wake.set()

    async def _shutdown(self) -> None:
        """Lets every client that goes on reading receive what is queued for it, then closes the server."""
        last, moved_at = None, self._loop.time()
        while left := {client: client.queued_bytes + len(client.control) for client in self._clients
                       if client.data or client.control}:
            if left != last:
                last, moved_at = left, self._loop.time()
            elif self._loop.time() - moved_at >= CLOSE_STALL_S:
                break  # nobody read anything in that time: what is left would never arrive
            await asyncio.sleep(PERIOD_S)
        self._server.close()
        await self._server.wait_closed()

    def close(self) -> None:
        """Sends what is left, then stops the server."""
        self._stop.set()
        if self.session is not None:
            self._thread.join(timeout=5)
            self.pump()
        asyncio.run_coroutine_threadsafe(self._shutdown(), self._loop).result()
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._loop_thread.join()
        self._loop.close()
        self._writer.close()

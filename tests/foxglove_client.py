"""A Foxglove WebSocket client for tests, written from the protocol's description (``foxglove.sdk.v1``:
JSON ``advertise`` and ``subscribe``, binary message data), not from the SDK that serves it."""

import asyncio
import json
import struct
import threading

import websockets

MESSAGE_DATA = 0x01  # server -> client binary opcode: u32 subscription id, u64 log time, payload


class Client:
    """Subscribes to every channel the server advertises and keeps every message, on its own thread."""

    def __init__(self, port: int):
        self.port = port
        self.channels: dict[int, dict] = {}
        self.messages: dict[str, list[tuple[int, bytes]]] = {}
        self.ready = threading.Event()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=lambda: asyncio.run(self._run()), daemon=True)
        self.thread.start()

    async def _run(self) -> None:
        async with websockets.connect(f"ws://127.0.0.1:{self.port}", subprotocols=["foxglove.sdk.v1"],
                                      max_size=None) as socket:
            subscriptions: dict[int, str] = {}
            while not self.stop.is_set():
                try:
                    frame = await asyncio.wait_for(socket.recv(), 0.2)
                except asyncio.TimeoutError:
                    continue
                except websockets.ConnectionClosed:  # the bridge closed: everything sent has arrived
                    return
                if isinstance(frame, str):
                    message = json.loads(frame)
                    if message["op"] == "advertise":
                        new = []
                        for channel in message["channels"]:
                            self.channels[channel["id"]] = channel
                            subscriptions[channel["id"]] = channel["topic"]
                            new.append({"id": channel["id"], "channelId": channel["id"]})
                        await socket.send(json.dumps({"op": "subscribe", "subscriptions": new}))
                        self.ready.set()
                    continue
                if frame[0] == MESSAGE_DATA:
                    subscription, log_time = struct.unpack_from("<IQ", frame, 1)
                    self.messages.setdefault(subscriptions[subscription], []).append((log_time, frame[13:]))


def decoded(client: Client, topic: str) -> list:
    """``topic``'s messages as received, decoded with the schema the server advertised for it (protobuf:
    its FileDescriptorSet in base64, the protocol's rule for binary schemas), by the mcap library's decoder."""
    import base64

    from mcap.records import Schema
    from mcap_protobuf.decoder import DecoderFactory

    advertised = next(c for c in client.channels.values() if c["topic"] == topic)
    schema = Schema(id=0, name=advertised["schemaName"], encoding=advertised["schemaEncoding"],
                    data=base64.b64decode(advertised["schema"]))
    decode = DecoderFactory().decoder_for(advertised["encoding"], schema)
    return [decode(payload) for _, payload in client.messages[topic]]

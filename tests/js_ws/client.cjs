// Foxglove's own WebSocket client (@foxglove/ws-protocol's FoxgloveClient over the `ws` package) against
// the live bridge: node client.cjs URL SUBPROTOCOL [ORIGIN]
// Subscribes to every channel it is told of, prints {"event": "advertised", ...} once the first channels
// came, keeps every message, and when the connection closes prints one JSON line with what it got:
// the close code and reason, the errors, the status messages, the channels and, per topic, each
// message as [log time ns (a string), payload (text for json channels, else base64)].
"use strict";
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");

const [url, subprotocol, origin] = process.argv.slice(2);
const ws = new WebSocket(url, [subprotocol], origin ? { origin } : {});
const client = new FoxgloveClient({ ws });
const channels = new Map(); // channel id -> channel
const topics = new Map(); // subscription id -> channel
const got = { statuses: [], errors: [], serverInfo: null, channels: [], messages: {}, protocol: null };

client.on("open", () => { got.protocol = ws.protocol; });
client.on("serverInfo", (info) => { got.serverInfo = info; });
client.on("status", (status) => { got.statuses.push(status); });
client.on("error", (error) => { got.errors.push(String(error && error.message ? error.message : error)); });
client.on("advertise", (advertised) => {
  for (const channel of advertised) {
    channels.set(channel.id, channel);
    got.channels.push(channel);
    topics.set(client.subscribe(channel.id), channel);
  }
  process.stdout.write(JSON.stringify({ event: "advertised", topics: advertised.map((c) => c.topic) }) + "\n");
});
const decoder = new TextDecoder();
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const channel = topics.get(subscriptionId);
  const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
  const payload = channel.encoding === "json" ? decoder.decode(bytes) : Buffer.from(bytes).toString("base64");
  (got.messages[channel.topic] ??= []).push([timestamp.toString(), payload]);
});
client.on("close", (event) => {
  got.code = event.code;
  got.reason = String(event.reason ?? "");
  process.stdout.write(JSON.stringify({ event: "closed", ...got }) + "\n", () => process.exit(0));
});

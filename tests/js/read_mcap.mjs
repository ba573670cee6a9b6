// node read_mcap.mjs FILE.mcap: reads every message of every channel with Foxglove's @mcap/core (the
// indexed reader, as Foxglove and Lichtblick open a file) and decodes it as Lichtblick does
// (lichtblick_parse.mjs); prints, as JSON, per topic: the schema, whether Lichtblick takes it (or its
// error), the message count, the first and last log time, and per top-level number field the count of finite
// values and their sum; and the file's metadata.
import { open } from "node:fs/promises";
import { McapIndexedReader } from "@mcap/core";
import { decompress } from "fzstd";
import { parseChannel } from "./lichtblick_parse.mjs";

const handle = await open(process.argv[2], "r");
const readable = {
  size: async () => BigInt((await handle.stat()).size),
  read: async (offset, length) => {
    const buffer = new Uint8Array(Number(length));
    await handle.read(buffer, 0, Number(length), Number(offset));
    return buffer;
  },
};
const reader = await McapIndexedReader.Initialize({
  readable,
  decompressHandlers: { zstd: (data, size) => decompress(data, new Uint8Array(Number(size))) },
});

const topics = {};
const parsed = new Map();
for (const channel of reader.channelsById.values()) {
  const schema = reader.schemasById.get(channel.schemaId);
  const entry = {
    schemaName: schema?.name, schemaEncoding: schema?.encoding, messageEncoding: channel.messageEncoding,
    count: 0, firstLogTime: null, lastLogTime: null, fields: {}, sums: {},
  };
  try {
    const channelParse = parseChannel({ messageEncoding: channel.messageEncoding, schema });
    parsed.set(channel.id, channelParse);
    const root = channelParse.datatypes.get(schema?.name);
    for (const field of root?.definitions ?? []) entry.fields[field.name] = field.type;
  } catch (error) {
    entry.error = String(error.message ?? error);
  }
  topics[channel.topic] = entry;
}

for await (const message of reader.readMessages()) {
  const channel = reader.channelsById.get(message.channelId);
  const entry = topics[channel.topic];
  entry.firstLogTime ??= String(message.logTime);
  entry.lastLogTime = String(message.logTime);
  entry.count += 1;
  const channelParse = parsed.get(message.channelId);
  if (channelParse === undefined) continue;
  const value = channelParse.deserialize(message.data);
  for (const [name, v] of Object.entries(value)) {
    if (typeof v !== "number") continue;
    const sum = (entry.sums[name] ??= [0, 0]);
    if (Number.isFinite(v)) {
      sum[0] += 1;
      sum[1] += v;
    }
  }
}

const metadata = {};
for await (const record of reader.readMetadata()) metadata[record.name] = Object.fromEntries(record.metadata);
await handle.close();
process.stdout.write(JSON.stringify({ topics, metadata }));

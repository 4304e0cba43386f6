// Reads an MCAP file with Foxglove's TypeScript reader (@mcap/core from the npm registry, not the
// project's code) twice: record by record (McapStreamReader, every chunk CRC checked) and through the
// summary's indexes (McapIndexedReader: footer -> summary -> chunk indexes -> message indexes).
// Prints one JSON object: per topic its schema, encodings and message counts by both paths, and the
// file's Statistics record. JSON channels whose schema is one of Foxglove's (foxglove.SceneUpdate, ...)
// are validated message by message against Foxglove's published JSON schemas (@foxglove/schemas) with
// ajv: per topic, how many messages passed and the first error. Usage: NODE_PATH=<dir>/node_modules node mcap_check.cjs FILE.mcap
"use strict";
const fs = require("fs");
const { McapStreamReader, McapIndexedReader } = require("@mcap/core");

async function main() {
  const file = process.argv[2];
  const bytes = fs.readFileSync(file);
  const out = { channels: {}, stream: {}, indexed: {}, statistics: null, schemas: {} };

  const stream = new McapStreamReader({ validateCrcs: true });
  stream.append(new Uint8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength));
  const streamChannels = new Map();
  let record;
  let sawFooter = false;
  while ((record = stream.nextRecord())) {
    if (record.type === "Schema") out.schemas[record.id] = { name: record.name, encoding: record.encoding, bytes: record.data.length };
    if (record.type === "Channel") streamChannels.set(record.id, record.topic);
    if (record.type === "Message") {
      const topic = streamChannels.get(record.channelId);
      out.stream[topic] = (out.stream[topic] || 0) + 1;
    }
    if (record.type === "Footer") sawFooter = true;
  }
  if (!sawFooter || !stream.done()) throw new Error("the stream reader did not reach the footer");

  const fd = fs.openSync(file, "r");
  const readable = {
    size: async () => BigInt(bytes.byteLength),
    read: async (offset, size) => {
      const buf = Buffer.alloc(Number(size));
      fs.readSync(fd, buf, 0, Number(size), Number(offset));
      return new Uint8Array(buf.buffer, buf.byteOffset, buf.byteLength);
    },
  };
  const indexed = await McapIndexedReader.Initialize({ readable });
  for (const [id, ch] of indexed.channelsById) {
    const schema = indexed.schemasById.get(ch.schemaId);
    out.channels[ch.topic] = {
      id,
      schema: schema ? schema.name : null,
      schemaEncoding: schema ? schema.encoding : null,
      messageEncoding: ch.messageEncoding,
      metadata: Object.fromEntries(ch.metadata),
    };
  }
  const Ajv = require("ajv");
  const foxgloveSchemas = require("@foxglove/schemas/jsonschema");
  const ajv = new Ajv({ strict: false, allErrors: false });
  const validators = new Map();
  out.json = {};
  let lastLogTime = 0n;
  let ordered = true;
  for await (const m of indexed.readMessages()) {
    const topic = indexed.channelsById.get(m.channelId).topic;
    out.indexed[topic] = (out.indexed[topic] || 0) + 1;
    const channel = indexed.channelsById.get(m.channelId);
    if (channel.messageEncoding === "json") {
      const schemaName = indexed.schemasById.get(channel.schemaId).name;
      const j = (out.json[topic] = out.json[topic] || { schema: schemaName, valid: 0, invalid: 0, firstError: null });
      const message = JSON.parse(Buffer.from(m.data).toString("utf8"));
      const official = schemaName.startsWith("foxglove.") ? foxgloveSchemas[schemaName.slice("foxglove.".length)] : undefined;
      if (official) {
        if (!validators.has(schemaName)) validators.set(schemaName, ajv.compile(official));
        const validate = validators.get(schemaName);
        if (validate(message)) j.valid++;
        else {
          j.invalid++;
          if (!j.firstError) j.firstError = ajv.errorsText(validate.errors);
        }
      } else if (typeof message === "object") j.valid++;
      j.last = message;
    }
    if (m.logTime < lastLogTime) ordered = false;
    lastLogTime = m.logTime;
  }
  out.indexedInLogTimeOrder = ordered;
  // The last cloth and latency messages, reduced to what a test checks (the cloth's JSON is large).
  for (const [topic, j] of Object.entries(out.json)) {
    const m = j.last;
    delete j.last;
    if (j.schema === "foxglove.SceneUpdate" && m.entities.length > 0) {
      const e = m.entities[0];
      j.lastTriangles = e.triangles.length ? e.triangles[0].indices.length / 3 : 0;
      j.lastPoints = e.triangles.length ? e.triangles[0].points.length : 0;
      j.lastLines = e.lines.map((l) => l.points.length);
    } else j.lastMessage = m;
  }
  const s = indexed.statistics;
  if (s) {
    out.statistics = {
      messageCount: Number(s.messageCount),
      schemaCount: s.schemaCount,
      channelCount: s.channelCount,
      chunkCount: s.chunkCount,
      channelMessageCounts: Object.fromEntries([...s.channelMessageCounts].map(([id, n]) => [indexed.channelsById.get(id).topic, Number(n)])),
    };
  }
  out.chunkIndexes = indexed.chunkIndexes.length;
  fs.closeSync(fd);
  process.stdout.write(JSON.stringify(out) + "\n");
}

main().catch((e) => {
  process.stderr.write(`mcap_check: ${e.stack || e}\n`);
  process.exit(1);
});

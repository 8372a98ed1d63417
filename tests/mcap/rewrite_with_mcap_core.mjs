// Writes an MCAP file CSP exported again with npm's @mcap/core McapWriter, as another program would
// write it: chunked (small chunks) or not (messages in the data section, no chunk index), with an
// attachment and a channel CSP does not know. CSP's reader must read it (export_and_read.cmake).
//
//   node rewrite_with_mcap_core.mjs IN.mcap OUT.mcap CHUNKED(0|1)
import { readFile, writeFile } from "node:fs/promises";
import { fileURLToPath } from "node:url";
import path from "node:path";

const here = path.dirname(fileURLToPath(import.meta.url));
const core = path.join(here, "..", "..", "view", "web", "node_modules", "@mcap", "core", "dist", "esm", "index.js");
const { McapIndexedReader, McapWriter, TempBuffer } = await import(core);

const [input, output, chunkedText] = process.argv.slice(2);
if (!input || !output || !["0", "1"].includes(chunkedText)) {
  console.error("usage: node rewrite_with_mcap_core.mjs IN.mcap OUT.mcap CHUNKED(0|1)");
  process.exit(2);
}
const chunked = chunkedText === "1";

const bytes = new Uint8Array(await readFile(input));
const reader = await McapIndexedReader.Initialize({
  readable: {
    size: async () => BigInt(bytes.byteLength),
    read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
  },
});

const buffer = new TempBuffer();
const writer = new McapWriter({ writable: buffer, useChunks: chunked, chunkSize: 64 * 1024 });
await writer.start({ profile: "", library: "@mcap/core rewrite" });
const schemaIds = new Map();
for (const schema of reader.schemasById.values()) {
  schemaIds.set(schema.id, await writer.registerSchema({ name: schema.name, encoding: schema.encoding, data: schema.data }));
}
const channelIds = new Map();
for (const channel of reader.channelsById.values()) {
  channelIds.set(channel.id, await writer.registerChannel({
    topic: channel.topic,
    schemaId: schemaIds.get(channel.schemaId),
    messageEncoding: channel.messageEncoding,
    metadata: channel.metadata,
  }));
}
const other = await writer.registerChannel({ topic: "/other", schemaId: 0, messageEncoding: "json", metadata: new Map() });
for await (const metadata of reader.readMetadata()) await writer.addMetadata(metadata);
await writer.addAttachment({
  name: "notes.txt", logTime: 0n, createTime: 0n, mediaType: "text/plain", data: new TextEncoder().encode("not a row"),
});
let count = 0;
for await (const message of reader.readMessages()) {
  await writer.addMessage({ ...message, channelId: channelIds.get(message.channelId) });
  if (count++ === 0) await writer.addMessage({ ...message, channelId: other, data: new TextEncoder().encode("{}") });
}
await writer.end();
await writeFile(output, buffer.get());
console.log(`${path.basename(output)}: ${count} messages rewritten by @mcap/core (${chunked ? "chunked" : "no chunks"})`);

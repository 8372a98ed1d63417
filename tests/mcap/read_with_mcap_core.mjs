// Reads an MCAP file `csp log export --format mcap` wrote with the reference reader, npm's
// @mcap/core (view/web/node_modules: `npm ci --prefix view/web`), indexed and streamed, and checks
// what docs/mcap.md promises. Exits 1 with the reason on the first failed check.
//
//   node read_with_mcap_core.mjs FILE.mcap ROWS SCENE(0|1)
import { readFile } from "node:fs/promises";
import { fileURLToPath } from "node:url";
import path from "node:path";

const here = path.dirname(fileURLToPath(import.meta.url));
const core = path.join(here, "..", "..", "view", "web", "node_modules", "@mcap", "core", "dist", "esm", "index.js");
const { McapIndexedReader, McapStreamReader } = await import(core);

const [file, rowsText, sceneText] = process.argv.slice(2);
const rows = Number(rowsText);
const withScene = sceneText === "1";
if (!file || !Number.isInteger(rows) || rows < 2) {
  console.error("usage: node read_with_mcap_core.mjs FILE.mcap ROWS SCENE(0|1)");
  process.exit(2);
}

function check(condition, what) {
  if (!condition) {
    console.error(`${file}: ${what}`);
    process.exit(1);
  }
}

const bytes = new Uint8Array(await readFile(file));
const readable = {
  size: async () => BigInt(bytes.byteLength),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};
const reader = await McapIndexedReader.Initialize({ readable });

check(reader.header.library === "csp log export", `header library ${JSON.stringify(reader.header.library)}`);
check(reader.chunkIndexes.length > 0, "no chunk indexes");

// Schemas: the expected names, JSON schemas that parse; their `required` lists checked below.
const expectedSchemas = ["csp.JointState", "foxglove.FrameTransforms", "foxglove.Log"];
if (withScene) expectedSchemas.push("foxglove.SceneUpdate");
const schemaByName = new Map();
for (const schema of reader.schemasById.values()) {
  check(schema.encoding === "jsonschema", `schema ${schema.name}: encoding ${schema.encoding}`);
  schemaByName.set(schema.name, JSON.parse(new TextDecoder().decode(schema.data)));
}
check(
  JSON.stringify([...schemaByName.keys()].sort()) === JSON.stringify([...expectedSchemas].sort()),
  `schemas ${[...schemaByName.keys()]}, expected ${expectedSchemas}`,
);

// Channels: topic -> schema name.
const expectedTopics = { "/joint_states": "csp.JointState", "/tf": "foxglove.FrameTransforms", "/errors": "foxglove.Log" };
if (withScene) expectedTopics["/scene"] = "foxglove.SceneUpdate";
const topicById = new Map();
for (const channel of reader.channelsById.values()) {
  const schema = reader.schemasById.get(channel.schemaId);
  check(channel.messageEncoding === "json", `channel ${channel.topic}: message encoding ${channel.messageEncoding}`);
  check(expectedTopics[channel.topic] === schema?.name, `channel ${channel.topic} with schema ${schema?.name}`);
  topicById.set(channel.id, channel.topic);
}
check(topicById.size === Object.keys(expectedTopics).length, `channels ${[...topicById.values()]}`);

// Every message parses as JSON and has its schema's required fields (and those of the arrays' items).
function missingRequired(schema, value, where) {
  for (const key of schema.required ?? []) if (!(key in value)) return `${where}: no ${key}`;
  for (const [key, property] of Object.entries(schema.properties ?? {})) {
    if (property.type === "array" && property.items?.required && Array.isArray(value[key])) {
      for (const [i, item] of value[key].entries()) {
        const missing = missingRequired(property.items, item, `${where}.${key}[${i}]`);
        if (missing) return missing;
      }
    }
  }
  return undefined;
}

const indexedCounts = new Map();
let lastTime = -1n;
for await (const message of reader.readMessages({ validateCrcs: true })) {
  const topic = topicById.get(message.channelId);
  indexedCounts.set(topic, (indexedCounts.get(topic) ?? 0) + 1);
  check(message.logTime >= lastTime, `${topic}: log time ${message.logTime} before ${lastTime}`);
  lastTime = message.logTime;
  const value = JSON.parse(new TextDecoder().decode(message.data));
  const missing = missingRequired(schemaByName.get(expectedTopics[topic]), value, `${topic} message`);
  check(!missing, missing);
  if (topic === "/joint_states") {
    check(value.name.length === 7 && value.position.length === 7 && value.velocity.length === 7 && value.effort.length === 7,
          "/joint_states: name, position, velocity, effort of 7 joints");
    const ns = BigInt(value.timestamp.sec) * 1000000000n + BigInt(value.timestamp.nsec);
    check(ns === message.logTime, `/joint_states: timestamp ${ns} is not the log time ${message.logTime}`);
  }
}
check(indexedCounts.get("/joint_states") === rows, `/joint_states: ${indexedCounts.get("/joint_states")} messages, expected ${rows}`);
check(indexedCounts.get("/tf") === rows, `/tf: ${indexedCounts.get("/tf")} messages, expected ${rows}`);
if (withScene) check(indexedCounts.get("/scene") === 1, `/scene: ${indexedCounts.get("/scene")} messages, expected 1`);

// The statistics agree with what the index gave.
const statistics = reader.statistics;
check(statistics !== undefined, "no Statistics record");
for (const [id, count] of statistics.channelMessageCounts) {
  check(Number(count) === (indexedCounts.get(topicById.get(id)) ?? 0), `statistics: ${topicById.get(id)} ${count}`);
}

// The session record.
let session;
for await (const metadata of reader.readMetadata({ name: "csp.session" })) session = metadata.metadata;
check(session?.get("robot_text")?.length > 0, "no csp.session metadata with the robot file's text");

// The stream reader: the same messages, every CRC checked.
const stream = new McapStreamReader({ validateCrcs: true });
stream.append(bytes);
const streamedCounts = new Map();
for (let record; (record = stream.nextRecord()); ) {
  if (record.type !== "Message") continue;
  const topic = topicById.get(record.channelId);
  streamedCounts.set(topic, (streamedCounts.get(topic) ?? 0) + 1);
}
check(stream.done(), "the stream reader did not reach the end");
for (const [topic, count] of indexedCounts)
  check(streamedCounts.get(topic) === count, `stream reader: ${topic} ${streamedCounts.get(topic)}, indexed ${count}`);

const counts = [...indexedCounts].map(([topic, count]) => `${topic} ${count}`).join(", ");
console.log(`${path.basename(file)}: @mcap/core read ${reader.chunkIndexes.length} chunks (indexed and streamed): ${counts}`);

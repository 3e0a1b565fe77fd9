// `sweepmap export mcap` read back by an independent reader (@mcap/core): the indexed reader
// (summary, chunk indexes, message indexes: what a seeking reader uses) and the stream reader
// (every record in order, CRCs checked) see the same messages; every LCM channel of the logs is
// there raw with its count; every derived topic has its Foxglove schema, its count follows from
// the logs' LCM counts, and each of its messages validates against that JSON schema.
// /sweep_cloud's points carry a float32 intensity field on every message when EXPECT_INTENSITY=all
// (a lidar that measures it), on none when EXPECT_INTENSITY=none, and its values are finite
// and >= 0.
// Usage: [EXPECT_INTENSITY=all|none] node export_mcap.test.js MCAP LOG... (the logs the file
// was exported from)
"use strict";
const fs = require("fs");
const { execFileSync } = require("child_process");
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { readLcmLog, validate, check } = require("./readers_common.js");

// Node 20's zlib has no zstd: the zstd program decompresses (the test's only external tool).
const decompressHandlers = {
  zstd: (data, size) => new Uint8Array(execFileSync("zstd", ["-d", "-c", "-q"], { input: data, maxBuffer: Number(size) + 1024 })),
};

async function readIndexed(buf) {
  const readable = {
    size: async () => BigInt(buf.length),
    read: async (offset, length) => buf.subarray(Number(offset), Number(offset + length)),
  };
  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  const messages = [];
  for await (const m of reader.readMessages({ validateCrcs: true })) messages.push(m);
  return { reader, messages };
}

function readStream(buf) {
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  reader.append(buf);
  const records = [];
  for (let r; (r = reader.nextRecord()); ) records.push(r);
  check(reader.done(), "the stream reader reached the end magic");
  return records;
}

// The derived topics' counts that the LCM channels' counts imply.
function expectedDerived(lcm) {
  const n = (c) => lcm.get(c) || 0;
  let status = 0;
  for (const [c, k] of lcm) if (c.startsWith("STATUS_")) status += k;
  return {
    "/sweep_cloud": n("SWEEP_CLOUD"),
    "/pose": n("ODOMETRY_POSE"),
    "/wheel_odometry": n("WHEEL_ODOMETRY"),
    "/truth_pose": n("TRUTH_POSE"),
    "/profile": n("PROFILE"),
    "/status": status,
    lidar: n("LIDAR_SCAN"),
  };
}

// Whether a foxglove.PointCloud message has an intensity field; checks its layout and values.
function cloudIntensity(msg, topic) {
  const field = msg.fields.find((f) => f.name === "intensity");
  if (!field) return false;
  check(field.type === 7 && msg.point_stride === 16 && field.offset === 12, `${topic}: intensity field layout`);
  const data = Buffer.from(msg.data, "base64");
  for (let at = 12; at < data.length; at += 16) {
    const v = data.readFloatLE(at);
    check(Number.isFinite(v) && v >= 0, `${topic}: intensity ${v}`);
  }
  return true;
}

async function main() {
  const [mcapPath, ...logs] = process.argv.slice(2);
  const buf = fs.readFileSync(mcapPath);
  const lcm = new Map();
  for (const log of logs) for (const [c, k] of readLcmLog(log)) lcm.set(c, (lcm.get(c) || 0) + k);

  const { reader, messages } = await readIndexed(buf);
  const stream = readStream(buf);
  const streamed = stream.filter((r) => r.type === "Message");
  check(streamed.length === messages.length, `stream ${streamed.length} = indexed ${messages.length}`);
  const stats = reader.statistics;
  check(Number(stats.messageCount) === messages.length, "statistics.messageCount");
  check(Number(stats.chunkCount) === reader.chunkIndexes.length && stats.chunkCount > 0, "chunks");

  const counts = new Map();
  let withIntensity = 0;
  for (const m of messages) {
    const channel = reader.channelsById.get(m.channelId);
    if (channel.topic === "/sweep_cloud") withIntensity += cloudIntensity(JSON.parse(Buffer.from(m.data)), channel.topic);
    counts.set(channel.topic, (counts.get(channel.topic) || 0) + 1);
    check(stats.channelMessageCounts.get(m.channelId) > 0n, "channel count");
    if (channel.messageEncoding === "json") {
      const schema = reader.schemasById.get(channel.schemaId);
      const errors = validate(JSON.parse(Buffer.from(schema.data).toString()), JSON.parse(Buffer.from(m.data)));
      check(errors.length === 0, `${channel.topic}: ${errors.join("; ")}`);
    }
  }
  for (const [c, k] of lcm) check(counts.get(c) === k, `raw ${c}: ${counts.get(c)} of ${k}`);
  const want = expectedDerived(lcm);
  for (const [topic, k] of Object.entries(want)) {
    if (topic !== "lidar") check((counts.get(topic) || 0) === k, `${topic}: ${counts.get(topic)} != ${k}`);
  }
  const scans = (counts.get("/lidar_scan") || 0) + (counts.get("/lidar_points") || 0);
  check(scans === want.lidar, `lidar scans ${scans} != ${want.lidar}`);
  check((counts.get("/tf") || 0) > 0, "/tf holds the rig's frames");
  const expect = process.env.EXPECT_INTENSITY;
  if (expect === "all") check(withIntensity === want["/sweep_cloud"] && withIntensity > 0, `intensity on ${withIntensity} of ${want["/sweep_cloud"]} clouds`);
  if (expect === "none") check(withIntensity === 0, `intensity on ${withIntensity} clouds of a lidar without`);
  if (want["/sweep_cloud"] > 0) check(counts.get("/map") > 0, "a /map (the mapper's MAP_UPDATE, else the clouds)");

  const schemaOf = { "/sweep_cloud": "foxglove.PointCloud", "/map": "foxglove.PointCloud",
    "/lidar_points": "foxglove.PointCloud", "/profile": "foxglove.PointCloud",
    "/pose": "foxglove.PoseInFrame", "/tf": "foxglove.FrameTransform",
    "/lidar_scan": "foxglove.LaserScan", "/status": "foxglove.Log" };
  for (const channel of reader.channelsById.values()) {
    const schema = reader.schemasById.get(channel.schemaId);
    if (schemaOf[channel.topic]) check(schema && schema.name === schemaOf[channel.topic], channel.topic);
    if (channel.messageEncoding === "lcm") check(!schema || schema.encoding === "lcm", channel.topic);
  }
  console.log(JSON.stringify({ bytes: buf.length, messages: messages.length,
    chunks: reader.chunkIndexes.length, clouds_with_intensity: withIntensity, topics: Object.fromEntries(counts) }));
}

main().catch((e) => { console.error(e.stack || String(e)); process.exit(1); });

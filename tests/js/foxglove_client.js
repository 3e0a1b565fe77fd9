// The Foxglove WebSocket protocol of `sweepmap view`, through the reference client
// (@foxglove/ws-protocol's FoxgloveClient over the `ws` package): node foxglove_client.js URL
// TIMEOUT_S TOPIC... Subscribes to every advertised channel (advertised at once or later), decodes
// each message of a JSON channel and validates it against the published schema of its schema
// name (@foxglove/schemas); of a raw LCM channel (encoding "lcm") it keeps the first message's
// bytes (hex) and every message's length, for the C++ test to check against the LCM types.
// Unsubscribes from the first channel after its first message. Ends when every TOPIC has had a
// message (and 1.5 s more) or at the timeout, and prints one JSON object: the server's info, the
// channels (with a raw channel's schema text), per topic the messages received and the schema
// problems found (for /map also each message's point count), and messages after the unsubscribe.
'use strict';
const { FoxgloveClient } = require('@foxglove/ws-protocol');
const WebSocket = require('ws');
const schemas = require('@foxglove/schemas/jsonschema');
const { validate } = require('./json_schema.js');

const [url, timeoutArg, ...expected] = process.argv.slice(2);
const out = { channels: [], topics: {}, errors: [], after_unsubscribe: 0 };
const client = new FoxgloveClient({ ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
const bySubscription = new Map();
let unsubscribed = null;

function finish() {
  client.close();
  process.stdout.write(JSON.stringify(out) + '\n');
  process.exit(0);
}
let finishing = false;
function allSeen() {
  return expected.every((t) => out.topics[t] && out.topics[t].messages > 0);
}

client.on('error', (e) => out.errors.push(String(e && e.message ? e.message : e)));
client.on('serverInfo', (info) => { out.server_info = info; });
client.on('advertise', (channels) => {
  for (const c of channels) {
    const raw = c.encoding === 'lcm';
    out.channels.push({ id: c.id, topic: c.topic, encoding: c.encoding, schemaName: c.schemaName,
      schemaEncoding: c.schemaEncoding, ...(raw ? { schema: c.schema } : {}) });
    out.topics[c.topic] = { messages: 0, problems: [], schema_known: false };
    if (raw) {
      Object.assign(out.topics[c.topic], { first_hex: null, min_bytes: Infinity, max_bytes: 0 });
      bySubscription.set(client.subscribe(c.id), { channel: c, raw });
      continue;
    }
    const published = schemas[c.schemaName.replace(/^foxglove\./, '')];
    out.topics[c.topic].schema_known = Boolean(published);
    out.topics[c.topic].schema_matches_published = published !== undefined &&
      JSON.stringify(JSON.parse(c.schema)) === JSON.stringify(published);
    bySubscription.set(client.subscribe(c.id), { channel: c, schema: published });
  }
});
client.on('message', ({ subscriptionId, data }) => {
  const sub = bySubscription.get(subscriptionId);
  if (!sub) return;
  if (unsubscribed === subscriptionId) { out.after_unsubscribe++; return; }
  const t = out.topics[sub.channel.topic];
  t.messages++;
  if (sub.raw) {
    const bytes = Buffer.from(data.buffer, data.byteOffset, data.byteLength);
    if (t.first_hex === null) t.first_hex = bytes.toString('hex');
    t.min_bytes = Math.min(t.min_bytes, bytes.length);
    t.max_bytes = Math.max(t.max_bytes, bytes.length);
  } else if (!checkJson(sub, t, data)) {
    return;
  }
  if (unsubscribed === null) {
    unsubscribed = subscriptionId;
    client.unsubscribe(subscriptionId);
  }
  if (!finishing && allSeen()) {
    finishing = true;
    setTimeout(finish, 1500);  // messages after the unsubscribe would show here
  }
});

// A JSON channel's message: parsed and validated against its published schema; false when it is
// not JSON.
function checkJson(sub, t, data) {
  let msg;
  try {
    msg = JSON.parse(new TextDecoder().decode(data));
  } catch (e) {
    t.problems.push(`not JSON: ${e.message}`);
    return false;
  }
  if (sub.schema && t.problems.length < 5) t.problems.push(...validate(sub.schema, msg).slice(0, 5));
  if (sub.channel.topic === '/map' && msg.point_stride > 0) {  // voxel centres per message
    (t.points = t.points || []).push(Buffer.from(msg.data, 'base64').length / msg.point_stride);
  }
  return true;
}
setTimeout(finish, Number(timeoutArg) * 1000);

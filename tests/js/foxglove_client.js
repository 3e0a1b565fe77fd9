// The Foxglove WebSocket protocol of `sweepmap view`, through the reference client
// (@foxglove/ws-protocol's FoxgloveClient over the `ws` package): node foxglove_client.js URL
// TIMEOUT_S TOPIC... Subscribes to every advertised channel, decodes each message (JSON) and
// validates it against the published schema of its schema name (@foxglove/schemas); unsubscribes
// from the first channel after its first message. Ends when every TOPIC has had a message (and
// 1.5 s more) or at the timeout, and prints one JSON object: the server's info, the channels, per
// topic the messages received and the schema problems found, and messages after the
// unsubscribe.
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
    out.channels.push({ id: c.id, topic: c.topic, encoding: c.encoding, schemaName: c.schemaName,
      schemaEncoding: c.schemaEncoding });
    out.topics[c.topic] = { messages: 0, problems: [], schema_known: false };
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
  let msg;
  try {
    msg = JSON.parse(new TextDecoder().decode(data));
  } catch (e) {
    t.problems.push(`not JSON: ${e.message}`);
    return;
  }
  if (sub.schema && t.problems.length < 5) t.problems.push(...validate(sub.schema, msg).slice(0, 5));
  if (unsubscribed === null) {
    unsubscribed = subscriptionId;
    client.unsubscribe(subscriptionId);
  }
  if (!finishing && allSeen()) {
    finishing = true;
    setTimeout(finish, 1500);  // messages after the unsubscribe would show here
  }
});
setTimeout(finish, Number(timeoutArg) * 1000);

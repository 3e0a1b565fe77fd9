// Shared by the reader tests: an LCM log's channel counts (read here, independently of
// sweepmap's reader), a JSON-schema check of the subset the Foxglove schemas use, and check().
"use strict";
const fs = require("fs");

function check(ok, what) {
  if (!ok) throw new Error("check failed: " + what);
}

// Channel -> number of events, by the LCM log format (big-endian: sync word 0xEDA1DA01,
// event number u64, utime u64, channel length u32, data length u32, channel, data).
function readLcmLog(path) {
  const b = fs.readFileSync(path);
  const counts = new Map();
  let at = 0;
  while (at + 28 <= b.length) {
    check(b.readUInt32BE(at) === 0xeda1da01, `${path}: sync word at byte ${at}`);
    const channelLength = b.readUInt32BE(at + 20);
    const dataLength = b.readUInt32BE(at + 24);
    const channel = b.toString("latin1", at + 28, at + 28 + channelLength);
    counts.set(channel, (counts.get(channel) || 0) + 1);
    at += 28 + channelLength + dataLength;
  }
  check(at === b.length, `${path}: ends on an event`);
  return counts;
}

// Errors of `value` against `schema` (type, required, properties, items, minimum, maximum,
// oneOf of consts, base64 content): the keywords of the @foxglove/schemas JSON schemas.
function validate(schema, value, path = "") {
  const errors = [];
  const type = schema.type;
  const is = {
    object: (v) => v !== null && typeof v === "object" && !Array.isArray(v),
    array: Array.isArray,
    string: (v) => typeof v === "string",
    number: (v) => typeof v === "number" && Number.isFinite(v),
    integer: Number.isInteger,
    boolean: (v) => typeof v === "boolean",
  };
  if (type && !is[type](value)) return [`${path}: not ${type}`];
  if (schema.oneOf && !schema.oneOf.some((o) => o.const === value)) errors.push(`${path}: not an enum value`);
  if (schema.minimum !== undefined && value < schema.minimum) errors.push(`${path}: below minimum`);
  if (schema.maximum !== undefined && value > schema.maximum) errors.push(`${path}: above maximum`);
  if (schema.contentEncoding === "base64" && !/^[A-Za-z0-9+/]*={0,2}$/.test(value)) errors.push(`${path}: not base64`);
  if (type === "object") {
    for (const k of schema.required || []) if (!(k in value)) errors.push(`${path}.${k}: missing`);
    for (const [k, s] of Object.entries(schema.properties || {})) {
      if (k in value) errors.push(...validate(s, value[k], `${path}.${k}`));
    }
  }
  if (type === "array" && schema.items) value.forEach((v, i) => errors.push(...validate(schema.items, v, `${path}[${i}]`)));
  return errors;
}

module.exports = { check, readLcmLog, validate };

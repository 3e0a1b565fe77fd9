// A validator for the JSON-schema keywords that @foxglove/schemas' schemas use (type,
// properties, required, items, oneOf, const, minimum, maximum, contentEncoding base64): tests
// need no other npm package. Returns the list of problems, each with its JSON path.
'use strict';

function typeOk(type, v) {
  switch (type) {
    case 'object': return v !== null && typeof v === 'object' && !Array.isArray(v);
    case 'array': return Array.isArray(v);
    case 'string': return typeof v === 'string';
    case 'number': return typeof v === 'number' && Number.isFinite(v);
    case 'integer': return Number.isInteger(v);
    case 'boolean': return typeof v === 'boolean';
    case 'null': return v === null;
    default: return false;
  }
}

function validate(schema, v, path = '$', problems = []) {
  if (schema.type !== undefined) {
    const types = Array.isArray(schema.type) ? schema.type : [schema.type];
    if (!types.some((t) => typeOk(t, v))) {
      problems.push(`${path}: ${JSON.stringify(v)?.slice(0, 40)} is not ${types.join('|')}`);
      return problems;
    }
  }
  if (schema.const !== undefined && v !== schema.const) problems.push(`${path}: not ${schema.const}`);
  if (schema.minimum !== undefined && v < schema.minimum) problems.push(`${path}: below ${schema.minimum}`);
  if (schema.maximum !== undefined && v > schema.maximum) problems.push(`${path}: above ${schema.maximum}`);
  if (schema.contentEncoding === 'base64' && !/^[A-Za-z0-9+/]*={0,2}$/.test(v)) {
    problems.push(`${path}: not base64`);
  }
  if (schema.oneOf) {
    const ok = schema.oneOf.filter((s) => validate(s, v, path, []).length === 0).length;
    if (ok !== 1) problems.push(`${path}: matches ${ok} of oneOf`);
  }
  for (const key of schema.required || []) {
    if (!(key in v)) problems.push(`${path}: no ${key}`);
  }
  if (schema.properties && typeOk('object', v)) {
    for (const [key, sub] of Object.entries(schema.properties)) {
      if (key in v) validate(sub, v[key], `${path}.${key}`, problems);
    }
  }
  if (schema.items && Array.isArray(v)) {
    v.forEach((item, i) => validate(schema.items, item, `${path}[${i}]`, problems));
  }
  return problems;
}

module.exports = { validate };

#!/usr/bin/env node
// sparkplug_peer.js: a test-only Sparkplug B 3.0 peer for drivegate's end-to-end tests.
//
// It subscribes to a real MQTT broker, decodes every Sparkplug payload and prints it as TAB
// separated lines on stdout; it publishes Sparkplug payloads (NCMD/DCMD) and raw text (STATE)
// on command from stdin. tests/support/sparkplug_peer.h drives it from C++ tests.
//
// Why it is independent of drivegate: nothing here comes from drivegate's tree (daemon/mqtt,
// proto/). The protobuf schema and the encoder are Eclipse Tahu's, from the npm package
// `sparkplug-payload` (Tahu's JavaScript library, with the code protobufjs generated from Tahu's
// own sparkplug_b.proto); MQTT is MQTT.js. A mistake in drivegate's .proto or encoder therefore
// shows up as a wrong line here instead of cancelling out.
//
// Decoding: payloads are decoded with Tahu's generated Payload type (the wire schema), and the
// value of each metric is read from the oneof field actually present on the wire and interpreted
// per the Sparkplug 3.0 datatype, instead of Tahu's decodePayload(), whose getValue() turns a
// UInt32 above 2^31 negative (Long.toInt), reads UInt32 only from long_value, and has no array
// types. Interpretation follows Tahu's Java reference implementation: Int8/Int16/Int32 are
// sign-extended 32-bit values in int_value (-5 is 4294967291 on the wire), Int64 is a
// two's-complement long_value, UInt32 may be in long_value (Tahu, Ignition) or int_value (the
// 3.0 text): column 7 says which field carried it.
//
// Usage: node sparkplug_peer.js --broker mqtt://127.0.0.1:PORT [--sub FILTER]... [--client-id ID]
//          [--ca FILE --cert FILE --key FILE] [--username U --password P] [--mqtt5]
//          [--reconnect-ms N] [--will-topic T --will-payload TEXT [--will-retain] [--will-qos N]]
//   --sub defaults to 'spBv1.0/#'; it may be repeated.
//
// Output lines (fields TAB separated; text fields escaped: \\ \t \n \r):
//   ready                                   connected and every subscription acknowledged
//   disconnected / reconnected              lost the broker / connected and resubscribed again
//   msg TOPIC SEQ TIMESTAMP RETAIN RECV N   a Sparkplug payload (SEQ/TIMESTAMP "-" when absent,
//                                           RETAIN 0|1, RECV unix seconds with microseconds,
//                                           N metrics), then N metric lines, then "end"
//   metric NAME ALIAS TYPE VALUE PROPS FIELD MTS FLAGS
//          NAME/ALIAS/TYPE "-" when absent; in NDATA/DDATA/NCMD/DCMD, a metric without a name or
//          datatype gets them from the last NBIRTH/DBIRTH of that node/device by alias (FLAGS
//          then says name_from_birth / type_from_birth); TYPE as the spec names it (Int16,
//          UInt32, Float, ...); VALUE decimal numbers (64-bit exact), true/false, text escaped,
//          "null" for is_null, arrays as [a,b,...], Bytes as hex; PROPS key=value;key=value
//          ("-" when none; keys and values also escape ';' and '=' with a backslash);
//          FIELD the oneof value field on the wire (int_value, long_value, ..., "-" none);
//          MTS the metric timestamp or "-"; FLAGS comma list (name_from_birth, type_from_birth,
//          historical, transient) or "-"
//   text TOPIC RETAIN TEXT                  STATE messages and any non-Sparkplug topic
//   error TOPIC MESSAGE                     a payload that did not decode (the peer goes on)
//   published TOPIC                         a publish command was sent to the broker
//   publish_failed TOPIC MESSAGE            a publish command failed
// Commands on stdin (TAB separated, one per line):
//   publish TOPIC JSON                      JSON as Tahu's encodePayload takes it; QoS 0, not
//                                           retained. 64-bit values (timestamp, seq, Int64/UInt64/
//                                           UInt32/DateTime values) may be given as decimal strings;
//                                           a Float or Double value "NaN", "Infinity", "-Infinity"
//                                           is that number
//   publish_retained TOPIC JSON             as publish, but retained (a command a broken host
//                                           left in the broker's store)
//   publish_repeat TOPIC COUNT JSON         as publish, COUNT times back to back (one encoding);
//                                           one "published" once the broker has them all
//   publish_text TOPIC TEXT RETAIN QOS      raw UTF-8 text (TEXT unescaped as above)
//   publish_hex TOPIC HEX RETAIN QOS        raw bytes, e.g. a garbage payload
"use strict";

const fs = require("fs");
const readline = require("readline");
const mqtt = require("mqtt");
const Long = require("long");
const sparkplug = require("sparkplug-payload").get("spBv1.0");
const Proto = require("sparkplug-payload/lib/sparkplugPayloadProto");

const Payload = Proto.org.eclipse.tahu.protobuf.Payload;

// ---- arguments ----------------------------------------------------------------------------
function parseArgs(argv) {
  const o = { subs: [], reconnectMs: 250, protocolVersion: 4 };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const next = () => {
      if (i + 1 >= argv.length) fail(`${a} needs a value`);
      return argv[++i];
    };
    switch (a) {
      case "--broker": o.broker = next(); break;
      case "--sub": o.subs.push(next()); break;
      case "--client-id": o.clientId = next(); break;
      case "--ca": o.ca = next(); break;
      case "--cert": o.cert = next(); break;
      case "--key": o.key = next(); break;
      case "--username": o.username = next(); break;
      case "--password": o.password = next(); break;
      case "--mqtt5": o.protocolVersion = 5; break;
      case "--reconnect-ms": o.reconnectMs = Number(next()); break;
      case "--will-topic": o.willTopic = next(); break;
      case "--will-payload": o.willPayload = next(); break;
      case "--will-retain": o.willRetain = true; break;
      case "--will-qos": o.willQos = Number(next()); break;
      case "-h": case "--help":
        process.stderr.write("usage: sparkplug_peer.js --broker URL [--sub FILTER]... [--client-id ID] " +
          "[--ca F --cert F --key F] [--username U --password P] [--mqtt5] [--reconnect-ms N] " +
          "[--will-topic T --will-payload TEXT [--will-retain] [--will-qos N]]\n");
        process.exit(0);
      default: fail(`unknown argument ${a}`);
    }
  }
  if (!o.broker) fail("--broker is required");
  if (o.subs.length === 0) o.subs.push("spBv1.0/#");
  return o;
}

function fail(message) {
  process.stderr.write(`sparkplug_peer: ${message}\n`);
  process.exit(2);
}

// ---- output -------------------------------------------------------------------------------
// stdout on a pipe is synchronous in Node on Linux: each write is flushed when it returns.
function emit(lines) {
  process.stdout.write(lines.join("\n") + "\n");
}

function esc(s) {
  return String(s).replace(/[\\\t\n\r]/g, (c) => ({ "\\": "\\\\", "\t": "\\t", "\n": "\\n", "\r": "\\r" })[c]);
}
// Keys and values inside the properties field also escape ';' and '='.
function escProp(s) {
  return esc(s).replace(/[;=]/g, (c) => "\\" + c);
}
function unesc(s) {
  return s.replace(/\\(.)/g, (_, c) => ({ t: "\t", n: "\n", r: "\r" })[c] ?? c);
}

function nowUnix() {
  const ms = performance.timeOrigin + performance.now();
  const us = Math.round(ms * 1000);
  const sec = Math.floor(us / 1e6);
  return `${sec}.${String(us - sec * 1e6).padStart(6, "0")}`;
}

// ---- datatypes (Sparkplug 3.0, 6.4.16) ----------------------------------------------------
const TYPE_NAMES = [
  "Unknown", "Int8", "Int16", "Int32", "Int64", "UInt8", "UInt16", "UInt32", "UInt64", "Float",
  "Double", "Boolean", "String", "DateTime", "Text", "UUID", "DataSet", "Bytes", "File",
  "Template", "PropertySet", "PropertySetList", "Int8Array", "Int16Array", "Int32Array",
  "Int64Array", "UInt8Array", "UInt16Array", "UInt32Array", "UInt64Array", "FloatArray",
  "DoubleArray", "BooleanArray", "StringArray", "DateTimeArray",
];
function typeName(code) {
  return TYPE_NAMES[code] ?? `Type${code}`;
}

const ONEOF_FIELD = {
  intValue: "int_value", longValue: "long_value", floatValue: "float_value",
  doubleValue: "double_value", booleanValue: "boolean_value", stringValue: "string_value",
  bytesValue: "bytes_value", datasetValue: "dataset_value", templateValue: "template_value",
  propertysetValue: "propertyset_value", propertysetsValue: "propertysets_value",
  extensionValue: "extension_value",
};

// protobufjs gives uint64 fields as Long (unsigned) when the long package is present, else as a
// number; both are printed exactly.
function asLong(v, unsigned) {
  if (Long.isLong(v)) return Long.fromBits(v.low, v.high, unsigned);
  return Long.fromValue(v, unsigned);
}
function u64(v) {
  return asLong(v, true).toString();
}

// The shortest decimal that reads back as the same 32-bit float (0.1f prints 0.1).
function floatText(f) {
  if (!Number.isFinite(f)) return String(f);
  for (let p = 1; p <= 9; p++) {
    const n = Number(f.toPrecision(p));
    if (Math.fround(n) === f) return String(n);
  }
  return String(f);
}

function hex(bytes) {
  return Buffer.from(bytes).toString("hex");
}

function jsonText(v) {
  return JSON.stringify(v, (_, x) => {
    if (Long.isLong(x)) return x.toString();
    if (x && x.type === "Buffer" && Array.isArray(x.data)) return hex(x.data);
    return x;
  });
}

function arrayText(type, bytes) {
  const b = Buffer.from(bytes);
  const out = [];
  const each = (size, read) => {
    if (b.length % size !== 0) throw new Error(`${typeName(type)} of ${b.length} bytes`);
    for (let i = 0; i < b.length; i += size) out.push(read(i));
  };
  switch (type) {
    case 22: each(1, (i) => b.readInt8(i)); break;
    case 23: each(2, (i) => b.readInt16LE(i)); break;
    case 24: each(4, (i) => b.readInt32LE(i)); break;
    case 25: each(8, (i) => b.readBigInt64LE(i).toString()); break;
    case 26: each(1, (i) => b.readUInt8(i)); break;
    case 27: each(2, (i) => b.readUInt16LE(i)); break;
    case 28: each(4, (i) => b.readUInt32LE(i)); break;
    case 29: each(8, (i) => b.readBigUInt64LE(i).toString()); break;
    case 30: each(4, (i) => floatText(b.readFloatLE(i))); break;
    case 31: each(8, (i) => String(b.readDoubleLE(i))); break;
    case 32: {  // 4-byte little-endian count, then the bits, most significant first
      const n = b.readUInt32LE(0);
      if (b.length < 4 + Math.ceil(n / 8)) throw new Error("BooleanArray too short");
      for (let i = 0; i < n; i++) out.push((b[4 + (i >> 3)] & (0x80 >> (i & 7))) ? "true" : "false");
      break;
    }
    case 33: {  // NUL-terminated UTF-8 strings
      let start = 0;
      for (let i = 0; i < b.length; i++) {
        if (b[i] === 0) { out.push(esc(b.subarray(start, i).toString("utf8")).replace(/[,\[\]]/g, (c) => "\\" + c)); start = i + 1; }
      }
      if (start !== b.length) throw new Error("StringArray without final NUL");
      break;
    }
    case 34: each(8, (i) => b.readBigUInt64LE(i).toString()); break;
    default: return hex(b);
  }
  return `[${out.join(",")}]`;
}

// The value of a Metric or PropertyValue (any message with the Sparkplug value oneof), as text.
// `field` is the protobufjs name of the oneof member set on the wire.
function valueText(type, obj, field, escapeFn) {
  if (obj.isNull === true) return "null";
  if (!field) return "-";
  const v = obj[field];
  switch (field) {
    case "intValue": {
      const u = v >>> 0;
      if (type === 1 || type === 2 || type === 3) return String(u | 0);
      return String(u);
    }
    case "longValue":
      if (type === 4) return asLong(v, false).toString();  // Int64: two's complement
      return u64(v);
    case "floatValue": return floatText(v);
    case "doubleValue": return String(v);
    case "booleanValue": return v ? "true" : "false";
    case "stringValue": return escapeFn(v);
    case "bytesValue": return type >= 22 && type <= 34 ? arrayText(type, v) : hex(v);
    case "datasetValue": return escapeFn(jsonText(decodeDataSet(v)));
    case "templateValue": return escapeFn(jsonText(Payload.Template.toObject(v, { longs: String, bytes: String })));
    case "propertysetValue": return escapeFn(`{${propsText(v)}}`);
    case "propertysetsValue": return escapeFn(`[${(v.propertyset || []).map((s) => `{${propsText(s)}}`).join(",")}]`);
    case "extensionValue": return "extension";
    default: return "-";
  }
}

function decodeDataSet(ds) {
  const types = ds.types || [];
  return {
    columns: ds.columns || [],
    types: types.map(typeName),
    rows: (ds.rows || []).map((r) => (r.elements || []).map((e, i) => {
      const f = e.value;
      return f ? valueText(types[i], e, f, (s) => s) : null;
    })),
  };
}

function propsText(ps) {
  if (!ps) return "";
  const keys = ps.keys || [];
  const values = ps.values || [];
  return keys.map((k, i) => {
    const pv = values[i];
    const t = pv && pv.type;
    const v = pv ? valueText(t, pv, pv.value, escProp) : "-";
    return `${escProp(k)}=${v}`;
  }).join(";");
}

// ---- birth certificates: alias -> {name, datatype} per edge node / device -----------------
const births = new Map();  // "group/node" or "group/node/device" -> Map(alias string -> {name, type})

function topicParts(topic) {
  const p = topic.split("/");
  if (p[0] !== "spBv1.0" || p.length < 4 || p[1] === "STATE") return null;
  const kinds = ["NBIRTH", "NDEATH", "DBIRTH", "DDEATH", "NDATA", "DDATA", "NCMD", "DCMD"];
  if (!kinds.includes(p[2])) return null;
  return { group: p[1], type: p[2], node: p[3], device: p[4] ?? "" };
}

function birthKey(t) {
  return t.device ? `${t.group}/${t.node}/${t.device}` : `${t.group}/${t.node}`;
}

// ---- receiving ----------------------------------------------------------------------------
function onMessage(topic, payload, packet) {
  const received = nowUnix();
  const retain = packet.retain ? "1" : "0";
  const t = topicParts(topic);
  if (!t) {
    emit([`text\t${topic}\t${retain}\t${esc(payload.toString("utf8"))}`]);
    return;
  }
  let p;
  try {
    p = Payload.decode(payload);
  } catch (e) {
    emit([`error\t${topic}\t${esc(e.message)}`]);
    return;
  }
  try {
    const key = birthKey(t);
    const isBirth = t.type === "NBIRTH" || t.type === "DBIRTH";
    if (t.type === "NBIRTH") {
      for (const k of births.keys()) if (k === key || k.startsWith(key + "/")) births.delete(k);
    }
    const aliases = isBirth ? new Map() : births.get(key) || new Map();
    const metrics = p.metrics || [];
    const lines = [];
    lines.push(["msg", topic, p.hasOwnProperty("seq") ? u64(p.seq) : "-",
      p.hasOwnProperty("timestamp") ? u64(p.timestamp) : "-", retain, received,
      String(metrics.length)].join("\t"));
    for (const m of metrics) {
      const flags = [];
      const alias = m.hasOwnProperty("alias") ? u64(m.alias) : null;
      let name = m.hasOwnProperty("name") ? m.name : null;
      let type = m.hasOwnProperty("datatype") ? m.datatype : null;
      if (isBirth) {
        if (alias !== null) aliases.set(alias, { name, type });
      } else if (alias !== null && aliases.has(alias)) {
        const b = aliases.get(alias);
        if (name === null && b.name !== null) { name = b.name; flags.push("name_from_birth"); }
        if (type === null && b.type !== null) { type = b.type; flags.push("type_from_birth"); }
      }
      if (m.isHistorical) flags.push("historical");
      if (m.isTransient) flags.push("transient");
      const field = m.value;  // protobufjs oneof getter: the member set on the wire
      lines.push(["metric", name === null ? "-" : esc(name), alias ?? "-",
        type === null ? "-" : typeName(type), valueText(type, m, field, esc),
        m.properties && (m.properties.keys || []).length ? propsText(m.properties) : "-",
        field ? ONEOF_FIELD[field] : "-", m.hasOwnProperty("timestamp") ? u64(m.timestamp) : "-",
        flags.length ? flags.join(",") : "-"].join("\t"));
    }
    lines.push("end");
    if (isBirth) births.set(key, aliases);
    emit(lines);
  } catch (e) {
    emit([`error\t${topic}\t${esc(e.message)}`]);
  }
}

// ---- publishing ---------------------------------------------------------------------------
const LONG_TYPES = { INT64: false, LONG: false, UINT32: true, UINT64: true, DATETIME: true };

// Decimal strings for 64-bit values become Long (JSON numbers lose precision past 2^53).
function longify(payload) {
  if (typeof payload.timestamp === "string") payload.timestamp = Long.fromString(payload.timestamp, true);
  if (typeof payload.seq === "string") payload.seq = Long.fromString(payload.seq, true);
  const fixMetrics = (metrics) => {
    for (const m of metrics || []) {
      const unsigned = LONG_TYPES[String(m.type || "").toUpperCase()];
      if (unsigned !== undefined && typeof m.value === "string") m.value = Long.fromString(m.value, unsigned);
      // JSON has no NaN or infinities: "NaN", "Infinity", "-Infinity" stand for them in a Float
      // or Double metric.
      const float = ["FLOAT", "DOUBLE"].includes(String(m.type || "").toUpperCase());
      if (float && ["NaN", "Infinity", "-Infinity"].includes(m.value)) m.value = Number(m.value);
      if (typeof m.timestamp === "string") m.timestamp = Long.fromString(m.timestamp, true);
      if (typeof m.alias === "string") m.alias = Long.fromString(m.alias, true);
      for (const pv of Object.values(m.properties || {})) {
        const u = LONG_TYPES[String(pv.type || "").toUpperCase()];
        if (u !== undefined && typeof pv.value === "string") pv.value = Long.fromString(pv.value, u);
      }
      if (m.value && typeof m.value === "object" && Array.isArray(m.value.metrics)) fixMetrics(m.value.metrics);
    }
  };
  fixMetrics(payload.metrics);
  return payload;
}

function publish(client, topic, body, opts) {
  client.publish(topic, body, opts, (err) => {
    if (err) emit([`publish_failed\t${topic}\t${esc(err.message)}`]);
    else emit([`published\t${topic}`]);
  });
}

function onCommand(client, line) {
  if (line === "") return;
  const f = line.split("\t");
  const topic = f[1] ?? "";
  try {
    switch (f[0]) {
      case "publish":
      case "publish_retained": {
        const body = Buffer.from(sparkplug.encodePayload(longify(JSON.parse(f.slice(2).join("\t")))));
        publish(client, topic, body, { qos: 0, retain: f[0] === "publish_retained" });
        break;
      }
      case "publish_repeat": {
        const count = Number(f[2] ?? 0);
        const body = Buffer.from(sparkplug.encodePayload(longify(JSON.parse(f.slice(3).join("\t")))));
        for (let i = 1; i < count; ++i) client.publish(topic, body, { qos: 0, retain: false });
        publish(client, topic, body, { qos: 0, retain: false });
        break;
      }
      case "publish_text":
        publish(client, topic, Buffer.from(unesc(f[2] ?? ""), "utf8"),
          { retain: f[3] === "1", qos: Number(f[4] ?? 0) });
        break;
      case "publish_hex":
        publish(client, topic, Buffer.from(f[2] ?? "", "hex"), { retain: f[3] === "1", qos: Number(f[4] ?? 0) });
        break;
      default:
        emit([`publish_failed\t${topic}\tunknown command ${esc(f[0])}`]);
    }
  } catch (e) {
    emit([`publish_failed\t${topic}\t${esc(e.message)}`]);
  }
}

// ---- main ---------------------------------------------------------------------------------
function main() {
  const o = parseArgs(process.argv.slice(2));
  const options = {
    clientId: o.clientId ?? `sparkplug-peer-${process.pid}`,
    clean: true,
    protocolVersion: o.protocolVersion,
    reconnectPeriod: o.reconnectMs,
    connectTimeout: 5000,
    resubscribe: false,  // subscribed again by hand on every connect, to know when it is done
  };
  if (o.ca) options.ca = fs.readFileSync(o.ca);
  if (o.cert) options.cert = fs.readFileSync(o.cert);
  if (o.key) options.key = fs.readFileSync(o.key);
  if (o.username !== undefined) options.username = o.username;
  if (o.password !== undefined) options.password = o.password;
  if (o.willTopic) {
    options.will = { topic: o.willTopic, payload: Buffer.from(o.willPayload ?? "", "utf8"),
      retain: !!o.willRetain, qos: o.willQos ?? 0 };
  }

  const client = mqtt.connect(o.broker, options);
  let everReady = false;
  let connected = false;

  client.on("connect", () => {
    connected = true;
    lastError = "";
    client.subscribe(o.subs, { qos: 0 }, (err, granted) => {
      const refused = (granted || []).filter((g) => g.qos === 128 || g.reasonCode >= 128);
      if (err || refused.length) {
        process.stderr.write(`sparkplug_peer: subscribe failed: ${err ? err.message : JSON.stringify(refused)}\n`);
        process.exit(3);
      }
      emit([everReady ? "reconnected" : "ready"]);
      everReady = true;
    });
  });
  client.on("close", () => {
    if (connected) emit(["disconnected"]);
    connected = false;
  });
  let lastError = "";
  client.on("error", (e) => {  // said once while it repeats (each reconnect attempt fails alike)
    if (e.message !== lastError) process.stderr.write(`sparkplug_peer: ${e.message}\n`);
    lastError = e.message;
  });
  client.on("message", onMessage);

  const rl = readline.createInterface({ input: process.stdin, terminal: false });
  rl.on("line", (line) => onCommand(client, line));
  rl.on("close", () => client.end(false, () => process.exit(0)));
  process.on("SIGTERM", () => client.end(false, () => process.exit(0)));
}

main();

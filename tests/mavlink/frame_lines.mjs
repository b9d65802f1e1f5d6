// The text form of MAVLink frames shared with the C++ tests (tests/mavlink/frame_lines.hpp says
// the format), and the node-mavlink side of it: message classes by name, values to and from
// text, random messages, encoding and splitting with node-mavlink. node-mavlink is a test peer
// of adaptseg::mavlink only (tests/mavlink/package.json pins it), never a library dependency.

import { Readable } from 'node:stream';
import { pipeline } from 'node:stream/promises';
import {
  minimal, common, MavLinkProtocolV1, MavLinkProtocolV2, MavLinkPacketSplitter, MavLinkPacketParser,
} from 'node-mavlink';

// The messages adaptseg::mavlink knows, by their names in the definitions.
export const MESSAGE_NAMES = [
  'HEARTBEAT', 'SYS_STATUS', 'GPS_RAW_INT', 'GLOBAL_POSITION_INT', 'MISSION_CURRENT', 'MISSION_ITEM_REACHED',
  'COMMAND_INT', 'COMMAND_LONG', 'COMMAND_ACK', 'SET_POSITION_TARGET_GLOBAL_INT', 'POSITION_TARGET_GLOBAL_INT',
  'HOME_POSITION', 'EXTENDED_SYS_STATE', 'STATUSTEXT', 'CAMERA_IMAGE_CAPTURED',
];

const REGISTRY = { ...minimal.REGISTRY, ...common.REGISTRY };
export const CLASS_BY_NAME = Object.fromEntries(Object.values(REGISTRY).map((c) => [c.MSG_NAME, c]));
export const CLASS_BY_ID = REGISTRY;

export function classOf(name) {
  const clazz = CLASS_BY_NAME[name];
  if (!clazz) throw new Error(`node-mavlink has no message ${name}`);
  return clazz;
}

const elementType = (field) => field.type.replace(/\[\]$/, '').replace('uint8_t_mavlink_version', 'uint8_t');
const isFloat = (t) => t === 'float' || t === 'double';
const is64 = (t) => t === 'uint64_t' || t === 'int64_t';

function numberText(type, v) {
  if (isFloat(type)) {
    if (Number.isNaN(v)) return 'NaN';
    if (v === Infinity) return 'Infinity';
    if (v === -Infinity) return '-Infinity';
    if (Object.is(v, -0)) return '-0';
  }
  return String(v);
}

function parseNumber(type, text) {
  if (is64(type)) return BigInt(text);
  if (isFloat(type)) {
    const special = { NaN: NaN, Infinity: Infinity, '-Infinity': -Infinity, '-0': -0 };
    const v = text in special ? special[text] : Number(text);
    if (Number.isNaN(v) && text !== 'NaN') throw new Error(`bad number ${text}`);
    return type === 'float' ? Math.fround(v) : v;
  }
  const v = Number(text);
  if (!Number.isInteger(v)) throw new Error(`bad integer ${text}`);
  return v;
}

const latin1Hex = (s) => Buffer.from(s, 'latin1').toString('hex');
const hexLatin1 = (h) => Buffer.from(h, 'hex').toString('latin1');

/** A field's value as the line's text. */
export function valueText(field, value) {
  const type = elementType(field);
  if (field.type === 'char[]') return latin1Hex(value);
  if (field.type.endsWith('[]')) return value.map((v) => numberText(type, v)).join(',');
  return numberText(type, value);
}

/** A line's text as a field's value. */
export function parseValue(field, text) {
  const type = elementType(field);
  if (field.type === 'char[]') return hexLatin1(text);
  if (field.type.endsWith('[]')) return text.split(',').map((t) => parseNumber(type, t));
  return parseNumber(type, text);
}

/** Same value: Object.is for numbers (NaN equals NaN, -0 differs from 0), element-wise for arrays. */
export function sameValue(a, b) {
  if (Array.isArray(a) && Array.isArray(b)) return a.length === b.length && a.every((x, i) => sameValue(x, b[i]));
  return Object.is(a, b) || (typeof a === 'bigint' && typeof b === 'bigint' && a === b);
}

export function toLine(name, header, bytes, msg) {
  const clazz = classOf(name);
  const fields = clazz.FIELDS.map((f) => `${f.source}=${valueText(f, msg[f.name])}`);
  return [name, header.seq, header.sysid, header.compid, Buffer.from(bytes).toString('hex'), ...fields].join(' ');
}

export function parseLines(text) {
  const lines = [];
  text.split('\n').forEach((raw, i) => {
    const line = raw.trim();
    if (!line || line.startsWith('#')) return;
    const [name, seq, sysid, compid, hex, ...tokens] = line.split(' ');
    const fields = {};
    for (const t of tokens) {
      const eq = t.indexOf('=');
      if (eq < 0) throw new Error(`line ${i + 1}: bad token ${t}`);
      fields[t.slice(0, eq)] = t.slice(eq + 1);
    }
    lines.push({ lineNumber: i + 1, name, header: { seq: +seq, sysid: +sysid, compid: +compid },
                 bytes: Buffer.from(hex, 'hex'), fields });
  });
  return lines;
}

/** The node-mavlink message a line describes (its fields set from the line's text). */
export function messageOfLine(line) {
  const clazz = classOf(line.name);
  const msg = new clazz();
  for (const f of clazz.FIELDS) {
    if (!(f.source in line.fields)) throw new Error(`line ${line.lineNumber}: ${line.name}.${f.source} missing`);
    msg[f.name] = parseValue(f, line.fields[f.source]);
  }
  return msg;
}

/** node-mavlink's MAVLink 2 frame of msg (signed with key at timestampMs if key is given). */
export function encodeV2(msg, header, { key = null, linkId = 0, timestampMs = 0 } = {}) {
  if (!key) return new MavLinkProtocolV2(header.sysid, header.compid).serialize(msg, header.seq);
  const protocol = new MavLinkProtocolV2(header.sysid, header.compid, MavLinkProtocolV2.IFLAG_SIGNED);
  return protocol.sign(protocol.serialize(msg, header.seq), linkId, key, timestampMs);
}

/** node-mavlink's MAVLink 1 frame of msg. */
export function encodeV1(msg, header) {
  return new MavLinkProtocolV1(header.sysid, header.compid).serialize(msg, header.seq);
}

/** Splits a byte stream, in the given chunks, with node-mavlink's splitter and parser. */
export async function splitWithNode(chunks) {
  const splitter = new MavLinkPacketSplitter({}, { onCrcError: () => {} });
  const packets = [];
  await pipeline(Readable.from(chunks.map((c) => Buffer.from(c))), splitter, new MavLinkPacketParser(),
    async (source) => { for await (const p of source) packets.push(p); });
  return { packets, valid: splitter.validPackages, invalid: splitter.invalidPackages,
           unknown: splitter.unknownPackagesCount };
}

/** A small deterministic generator (mulberry32): same seed, same messages, on any machine. */
export function makeRandom(seed) {
  let a = seed >>> 0;
  const u32 = () => {
    a = (a + 0x6D2B79F5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return (t ^ (t >>> 14)) >>> 0;
  };
  return { u32, uniform: () => u32() / 4294967296, int: (lo, hi) => lo + Math.floor((u32() / 4294967296) * (hi - lo + 1)) };
}

const scratch = Buffer.alloc(8);
function randomScalar(rng, type) {
  switch (type) {
    case 'uint8_t': return rng.u32() & 0xFF;
    case 'int8_t': return (rng.u32() & 0xFF) - 128;
    case 'uint16_t': return rng.u32() & 0xFFFF;
    case 'int16_t': return (rng.u32() & 0xFFFF) - 32768;
    case 'uint32_t': return rng.u32();
    case 'int32_t': return rng.u32() | 0;
    case 'uint64_t': return (BigInt(rng.u32()) << 32n) | BigInt(rng.u32());
    case 'int64_t': return BigInt.asIntN(64, (BigInt(rng.u32()) << 32n) | BigInt(rng.u32()));
    case 'float': {
      const pick = rng.int(0, 11);
      if (pick === 0) return NaN;
      if (pick === 1) return Infinity;
      if (pick === 2) return -Infinity;
      if (pick === 3) return -0;
      if (pick === 4) return Math.fround(1.401298464324817e-45);
      if (pick === 5) return Math.fround((rng.uniform() - 0.5) * 400);
      for (;;) {
        scratch.writeUInt32LE(rng.u32(), 0);
        const v = scratch.readFloatLE(0);
        if (Number.isFinite(v)) return v;
      }
    }
    default: throw new Error(`no generator for ${type}`);
  }
}

/**
 * A random node-mavlink message of class clazz: integers over their whole range, floats of any
 * finite bit pattern or a special value, texts of 0..N non-zero bytes; each field zero with
 * probability zeroP (so that trailing-zero truncation is exercised).
 */
export function randomMessage(clazz, rng, zeroP) {
  const msg = new clazz();
  for (const f of clazz.FIELDS) {
    const type = elementType(f);
    const zero = () => rng.uniform() < zeroP;
    const zeroOf = is64(type) ? 0n : 0;
    if (f.type === 'char[]') {
      let n = zero() ? 0 : rng.int(0, f.length);
      if (n > 0 && rng.int(0, 3) === 0) n = f.length;
      msg[f.name] = Array.from({ length: n }, () => String.fromCharCode(rng.int(1, 255))).join('');
    } else if (f.type.endsWith('[]')) {
      msg[f.name] = Array.from({ length: f.length }, () => (zero() ? zeroOf : randomScalar(rng, type)));
    } else {
      msg[f.name] = zero() ? zeroOf : randomScalar(rng, type);
    }
  }
  return msg;
}

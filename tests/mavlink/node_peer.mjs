#!/usr/bin/env node
// node-mavlink's side of the live cross-check of adaptseg::mavlink (CTest mavlink:node_peer,
// run by run_node_peer.sh). node-mavlink is a test peer only, never a library dependency.
//
//   node node_peer.mjs check FILE       decode the frames our codec wrote (line format:
//                                       frame_lines.hpp) with node-mavlink's splitter and parser:
//                                       every frame found, checksum valid, header and every field
//                                       as the line says, and node-mavlink encoding the same
//                                       values writes the same bytes
//   node node_peer.mjs write FILE [N]   write N random frames per message (and MAVLink 1 and
//                                       signed ones) for our codec to decode
//   node node_peer.mjs constants FILE   check our named constants ("MAV_CMD_DO_REPOSITION 192"
//                                       lines) against node-mavlink's enums
// Exit 0 if all is well, 1 with one line per problem otherwise.

import { readFileSync, writeFileSync } from 'node:fs';
import { common, minimal, MavLinkPacketSignature } from 'node-mavlink';
import {
  MESSAGE_NAMES, CLASS_BY_ID, classOf, encodeV1, encodeV2, makeRandom, messageOfLine, parseLines, parseValue,
  randomMessage, sameValue, splitWithNode, toLine, valueText,
} from './frame_lines.mjs';

const problems = [];
const problem = (text) => { if (problems.length < 50) console.error(`node_peer: ${text}`); problems.push(text); };

async function check(file) {
  const lines = parseLines(readFileSync(file, 'utf8'));
  // One stream, as a link delivers it, in chunks of 1 to 64 bytes.
  const stream = Buffer.concat(lines.map((l) => l.bytes));
  const rng = makeRandom(7);
  const chunks = [];
  for (let at = 0; at < stream.length;) {
    const n = rng.int(1, 64);
    chunks.push(stream.subarray(at, at + n));
    at += n;
  }
  const { packets, valid, invalid, unknown } = await splitWithNode(chunks);
  if (packets.length !== lines.length || valid !== lines.length || invalid !== 0 || unknown !== 0) {
    problem(`${file}: ${lines.length} frames written, node-mavlink found ${packets.length} ` +
            `(valid ${valid}, checksum or framing errors ${invalid}, unknown ids ${unknown})`);
  }
  let identical = 0;
  let zeroPayload = 0;
  lines.forEach((line, i) => {
    const packet = packets[i];
    if (!packet) return;
    const where = `line ${line.lineNumber} (${line.name})`;
    const h = packet.header;
    const clazz = CLASS_BY_ID[h.msgid];
    if (!clazz || clazz.MSG_NAME !== line.name) {
      problem(`${where}: node-mavlink read message id ${h.msgid}`);
      return;
    }
    if (h.seq !== line.header.seq || h.sysid !== line.header.sysid || h.compid !== line.header.compid) {
      problem(`${where}: header seq/sysid/compid ${h.seq}/${h.sysid}/${h.compid}, line says ` +
              `${line.header.seq}/${line.header.sysid}/${line.header.compid}`);
    }
    if (!packet.buffer.equals(line.bytes)) problem(`${where}: node-mavlink split off other bytes than the frame's`);
    const data = packet.protocol.data(packet.payload, clazz);
    for (const f of clazz.FIELDS) {
      if (!(f.source in line.fields)) { problem(`${where}: field ${f.source} missing from the line`); continue; }
      const want = parseValue(f, line.fields[f.source]);
      if (!sameValue(data[f.name], want)) {
        problem(`${where}: ${f.source} decoded ${valueText(f, data[f.name])}, line says ${line.fields[f.source]}`);
      }
    }
    if (Object.keys(line.fields).length !== clazz.FIELDS.length) {
      problem(`${where}: the line has ${Object.keys(line.fields).length} fields, node-mavlink's ${clazz.MSG_NAME} ${clazz.FIELDS.length}`);
    }
    // node-mavlink encoding the line's values: the same bytes, except that it sends an all-zero
    // payload with length 0 where MAVLink 2 (and adaptseg) keep its first byte.
    const theirs = encodeV2(messageOfLine(line), line.header);
    if (theirs.equals(line.bytes)) {
      identical += 1;
    } else if (theirs[1] === 0 && line.bytes[1] === 1 && line.bytes[10] === 0) {
      zeroPayload += 1;
    } else {
      problem(`${where}: node-mavlink encodes ${theirs.toString('hex')}, adaptseg wrote ${line.bytes.toString('hex')}`);
    }
  });
  console.log(`node_peer: ${file}: ${packets.length} of ${lines.length} frames decoded by node-mavlink ` +
              `(${MESSAGE_NAMES.filter((n) => lines.some((l) => l.name === n)).length} message types); ` +
              `${identical} byte-identical to node-mavlink's encoding, ${zeroPayload} all-zero payloads ` +
              `(node-mavlink: length 0, MAVLink 2 and adaptseg: 1)`);
}

function write(file, count) {
  const rng = makeRandom(20261127);
  const out = ['# Frames encoded by node-mavlink (node_peer.mjs write); line format: frame_lines.hpp'];
  let seq = 0;
  const header = () => ({ seq: (seq++) & 0xFF, sysid: rng.int(0, 255), compid: rng.int(0, 255) });
  const key = MavLinkPacketSignature.key('node peer');
  for (const name of MESSAGE_NAMES) {
    const clazz = classOf(name);
    for (let i = 0; i < count; ++i) {
      // The first all zeros (node-mavlink: a 0-byte payload), then few, some or most fields zero.
      const msg = randomMessage(clazz, rng, i === 0 ? 1 : [0, 0.3, 0.8][i % 3]);
      const h = header();
      out.push(toLine(name, h, encodeV2(msg, h), msg));
    }
    // Signed: the signature is skipped by adaptseg, the rest checked as any frame.
    for (let i = 0; i < 3; ++i) {
      const msg = randomMessage(clazz, rng, 0.3);
      const h = header();
      out.push(toLine(name, h, encodeV2(msg, h, { key, linkId: rng.int(0, 255), timestampMs: Date.UTC(2026, 0, 1) + i }), msg));
    }
  }
  // MAVLink 1 (node-mavlink writes every field, extensions included, which adaptseg reads too).
  for (const name of MESSAGE_NAMES.filter((n) => classOf(n).MSG_ID < 256)) {
    const msg = randomMessage(classOf(name), rng, 0.3);
    const h = header();
    out.push(toLine(name, h, encodeV1(msg, h), msg));
  }
  writeFileSync(file, `${out.join('\n')}\n`);
  console.log(`node_peer: ${file}: ${out.length - 1} frames written by node-mavlink`);
}

// Our constants' names (MAVLink's) -> node-mavlink's enums.
const ENUMS = [
  ['MAV_CMD_', common.MavCmd], ['MAV_RESULT_', common.MavResult], ['MAV_FRAME_', common.MavFrame],
  ['GPS_FIX_TYPE_', common.GpsFixType], ['MAV_MODE_FLAG_', minimal.MavModeFlag], ['MAV_TYPE_', minimal.MavType],
  ['MAV_AUTOPILOT_', minimal.MavAutopilot], ['MAV_STATE_', minimal.MavState],
  ['MAV_LANDED_STATE_', common.MavLandedState], ['MAV_VTOL_STATE_', common.MavVtolState],
  ['MAV_SEVERITY_', common.MavSeverity], ['MAV_COMP_ID_', minimal.MavComponent],
  ['POSITION_TARGET_TYPEMASK_', common.PositionTargetTypemask],
];

function constants(file) {
  let checked = 0;
  for (const line of readFileSync(file, 'utf8').split('\n').filter((l) => l && !l.startsWith('#'))) {
    const [name, value] = line.split(' ');
    const entry = ENUMS.find(([prefix]) => name.startsWith(prefix));
    if (!entry) { problem(`constant ${name}: no node-mavlink enum for it`); continue; }
    const [prefix, values] = entry;
    const key = [name.slice(prefix.length), name].find((k) => k in values);
    if (key === undefined) { problem(`constant ${name}: not in node-mavlink's enum`); continue; }
    if (values[key] !== Number(value)) problem(`constant ${name}: adaptseg ${value}, node-mavlink ${values[key]}`);
    checked += 1;
  }
  console.log(`node_peer: ${checked} constants equal to node-mavlink's enums`);
}

const [mode, file, count] = process.argv.slice(2);
if (mode === 'check' && file) await check(file);
else if (mode === 'write' && file) write(file, Number(count ?? 40));
else if (mode === 'constants' && file) constants(file);
else {
  console.error('usage: node node_peer.mjs check FILE | write FILE [N] | constants FILE');
  process.exit(2);
}
if (problems.length > 0) {
  console.error(`node_peer: ${problems.length} problem(s)`);
  process.exit(1);
}

#!/usr/bin/env node
// Writes tests/data/mavlink/node_frames.txt: frames node-mavlink encodes, with the values it was
// given, for test_mavlink's byte-for-byte comparison (the doctest test reads the file and needs
// no node). Regenerate after changing a message here:
//   (cd tests/mavlink && npm ci && node make_frames.mjs ../data/mavlink/node_frames.txt)
// The line format: tests/mavlink/frame_lines.hpp.

import { writeFileSync, readFileSync } from 'node:fs';
import { MavLinkPacketSignature } from 'node-mavlink';
import { classOf, encodeV1, encodeV2, toLine } from './frame_lines.mjs';

const out = process.argv[2];
if (!out) {
  console.error('usage: node make_frames.mjs OUT.txt');
  process.exit(2);
}

// A PX4 quadrotor (system 1, autopilot component 1) near Bonn, and a companion (191).
const px4 = { sysid: 1, compid: 1 };
const companion = { sysid: 1, compid: 191 };
const f = Math.fround;

function message(name, values) {
  const clazz = classOf(name);
  const msg = new clazz();
  const bySource = Object.fromEntries(clazz.FIELDS.map((fd) => [fd.source, fd]));
  for (const fd of clazz.FIELDS) msg[fd.name] = fd.type === 'char[]' ? '' : fd.type.endsWith('[]') ? Array(fd.length).fill(0) : (fd.type.startsWith('uint64') || fd.type.startsWith('int64') ? 0n : 0);
  for (const [source, v] of Object.entries(values)) {
    if (!bySource[source]) throw new Error(`${name} has no field ${source}`);
    msg[bySource[source].name] = v;
  }
  return msg;
}

// [comment, name, header, values, options]; options.v1: a MAVLink 1 frame; options.key: signed.
const frames = [
  ['PX4 heartbeat: quadrotor, armed, custom mode (main 4, sub 4) = auto mission', 'HEARTBEAT', { ...px4, seq: 0 },
    { type: 2, autopilot: 12, base_mode: 157, custom_mode: (4 << 16) | (4 << 24), system_status: 4, mavlink_version: 3 }],
  ['ArduPilot heartbeat: quadrotor, guided (custom mode 4), standby', 'HEARTBEAT', { ...px4, seq: 1 },
    { type: 2, autopilot: 3, base_mode: 89, custom_mode: 4, system_status: 3, mavlink_version: 3 }],
  ['the companion\'s heartbeat as MAVLink 1', 'HEARTBEAT', { ...companion, seq: 2 },
    { type: 18, autopilot: 8, base_mode: 0, custom_mode: 0, system_status: 4, mavlink_version: 3 }, { v1: true }],
  ['sys status, extensions zero: truncated to the base fields', 'SYS_STATUS', { ...px4, seq: 3 },
    { onboard_control_sensors_present: 0x3520FC2F, onboard_control_sensors_enabled: 0x3520FC2F,
      onboard_control_sensors_health: 0x3520FC2F, load: 312, voltage_battery: 15840, current_battery: 1250,
      battery_remaining: 78, drop_rate_comm: 0, errors_comm: 0, errors_count1: 0, errors_count2: 0,
      errors_count3: 0, errors_count4: 0 }],
  ['sys status with the extended sensor bits, battery unknown', 'SYS_STATUS', { ...px4, seq: 4 },
    { onboard_control_sensors_present: 1, onboard_control_sensors_enabled: 1, onboard_control_sensors_health: 1,
      load: 1000, voltage_battery: 65535, current_battery: -1, battery_remaining: -1, drop_rate_comm: 10000,
      errors_comm: 7, errors_count1: 1, errors_count2: 2, errors_count3: 3, errors_count4: 4,
      onboard_control_sensors_present_extended: 1, onboard_control_sensors_enabled_extended: 1,
      onboard_control_sensors_health_extended: 0 }],
  ['GPS fix with extensions (hdg_acc and yaw zero: truncated away)', 'GPS_RAW_INT', { ...px4, seq: 5 },
    { time_usec: 1732600000123456n, fix_type: 3, lat: 507332101, lon: 71038874, alt: 61230, eph: 121, epv: 180,
      vel: 503, cog: 27012, satellites_visible: 14, alt_ellipsoid: 108770, h_acc: 850, v_acc: 1300,
      vel_acc: 120, hdg_acc: 0, yaw: 0 }],
  ['fused position, descending over the field', 'GLOBAL_POSITION_INT', { ...px4, seq: 6 },
    { time_boot_ms: 912345, lat: 507332101, lon: 71038874, alt: 121230, relative_alt: 60000, vx: -150, vy: 20,
      vz: 35, hdg: 27012 }],
  ['mission current: only seq (MAVLink 2 truncates the zero extensions away)', 'MISSION_CURRENT', { ...px4, seq: 7 },
    { seq: 5 }],
  ['mission current with the plan ids', 'MISSION_CURRENT', { ...px4, seq: 8 },
    { seq: 12, total: 40, mission_state: 3, mission_mode: 1, mission_id: 0xDEADBEEF, fence_id: 0, rally_points_id: 77 }],
  ['mission item 300 reached', 'MISSION_ITEM_REACHED', { ...px4, seq: 9 }, { seq: 300 }],
  ['mission item 0 reached: an all-zero payload', 'MISSION_ITEM_REACHED', { ...px4, seq: 10 }, { seq: 0 }],
  ['reposition to a point 60 m above home, yaw unchanged (NaN)', 'COMMAND_INT', { ...companion, seq: 11 },
    { target_system: 1, target_component: 1, frame: 6, command: 192, current: 0, autocontinue: 0, param1: -1,
      param2: 1, param3: 0, param4: NaN, x: 507335000, y: 71041000, z: 60 }],
  ['arm', 'COMMAND_LONG', { ...companion, seq: 12 },
    { target_system: 1, target_component: 1, command: 400, confirmation: 0, param1: 1, param2: 0, param3: 0,
      param4: 0, param5: 0, param6: 0, param7: 0 }],
  ['GLOBAL_POSITION_INT at 10 Hz', 'COMMAND_LONG', { ...companion, seq: 13 },
    { target_system: 1, target_component: 1, command: 511, confirmation: 2, param1: 33, param2: 100000, param3: 0,
      param4: 0, param5: 0, param6: 0, param7: 0 }],
  ['takeoff to 30.5 m, odd parameters', 'COMMAND_LONG', { ...companion, seq: 14 },
    { target_system: 1, target_component: 1, command: 22, confirmation: 0, param1: f(0.1), param2: -0, param3: Infinity,
      param4: NaN, param5: f(50.7332101), param6: f(7.1038874), param7: 30.5 }],
  ['ack: accepted (extensions zero)', 'COMMAND_ACK', { ...px4, seq: 15 }, { command: 400, result: 0 }],
  ['ack: in progress, with every extension', 'COMMAND_ACK', { ...px4, seq: 16 },
    { command: 2000, result: 5, progress: 42, result_param2: -123456, target_system: 1, target_component: 191 }],
  ['position setpoint, position only', 'SET_POSITION_TARGET_GLOBAL_INT', { ...companion, seq: 17 },
    { time_boot_ms: 1000, target_system: 1, target_component: 1, coordinate_frame: 6, type_mask: 0xDF8,
      lat_int: 507335000, lon_int: 71041000, alt: 45.25, vx: 0, vy: 0, vz: 0, afx: 0, afy: 0, afz: 0, yaw: 0, yaw_rate: 0 }],
  ['the setpoint followed', 'POSITION_TARGET_GLOBAL_INT', { ...px4, seq: 18 },
    { time_boot_ms: 912400, coordinate_frame: 6, type_mask: 0xDF8, lat_int: 507335000, lon_int: 71041000, alt: 45.25,
      vx: f(0.5), vy: f(-0.25), vz: 0, afx: 0, afy: 0, afz: 0, yaw: f(1.5707964), yaw_rate: 0 }],
  ['home, orientation unknown (NaN), with time_usec', 'HOME_POSITION', { ...px4, seq: 19 },
    { latitude: 507332101, longitude: 71038874, altitude: 61230, x: 0, y: 0, z: f(-0.1), q: [NaN, NaN, NaN, NaN],
      approach_x: 0, approach_y: 0, approach_z: 0, time_usec: 18446744073709551615n }],
  ['in the air, not a VTOL', 'EXTENDED_SYS_STATE', { ...px4, seq: 20 }, { vtol_state: 0, landed_state: 2 }],
  ['status text', 'STATUSTEXT', { ...px4, seq: 21 }, { severity: 6, text: 'Takeoff detected' }],
  ['status text of exactly 50 bytes: no terminator', 'STATUSTEXT', { ...px4, seq: 22 },
    { severity: 4, text: 'Preflight Fail: Compass Sensor 0 missing, check it' }],
  ['status text, chunk 1 of a long text', 'STATUSTEXT', { ...px4, seq: 23 },
    { severity: 3, text: 'second chunk', id: 513, chunk_seq: 1 }],
  ['image captured (the message takes the whole 255 bytes)', 'CAMERA_IMAGE_CAPTURED', { sysid: 1, compid: 100, seq: 24 },
    { time_boot_ms: 912500, time_utc: 1732600001000000n, camera_id: 0, lat: 507332101, lon: 71038874, alt: 121230,
      relative_alt: 60000, q: [1, 0, 0, 0], image_index: 17, capture_result: 1,
      file_url: 'http://192.168.144.25/DCIM/100MEDIA/IMG_0017.JPG' }],
  ['signed heartbeat (key "adaptseg", link 7, 2025-01-01)', 'HEARTBEAT', { ...px4, seq: 25 },
    { type: 2, autopilot: 12, base_mode: 29, custom_mode: 0, system_status: 3, mavlink_version: 3 },
    { key: MavLinkPacketSignature.key('adaptseg'), linkId: 7, timestampMs: Date.UTC(2025, 0, 1) }],
  ['ATTITUDE (#30): a message adaptseg::mavlink does not know', 'ATTITUDE', { ...px4, seq: 26 },
    { time_boot_ms: 912600, roll: f(0.01), pitch: f(-0.02), yaw: f(1.5), rollspeed: 0, pitchspeed: 0, yawspeed: 0 }],
];

const version = JSON.parse(readFileSync(new URL('./node_modules/node-mavlink/package.json', import.meta.url))).version;
const lines = [
  `# Frames encoded by node-mavlink ${version}, with the values it was given (line format: tests/mavlink/frame_lines.hpp).`,
  '# Generated by tests/mavlink/make_frames.mjs; do not edit. The comment line before each frame says what it is.',
];
for (const [comment, name, header, values, options = {}] of frames) {
  const msg = message(name, values);
  const bytes = options.v1 ? encodeV1(msg, header) : encodeV2(msg, header, options);
  lines.push(`# ${comment}`);
  lines.push(toLine(name, header, bytes, msg));
}
writeFileSync(out, `${lines.join('\n')}\n`);
console.log(`${out}: ${frames.length} frames`);

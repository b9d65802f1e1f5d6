#!/usr/bin/env node
// An emulated autopilot for the live test of adaptseg::mavlink's VehicleLink (CTest
// mavlink:emulator, run_link_emulator.sh), written with node-mavlink (a test peer pinned in
// package.json, never a library dependency). It speaks MAVLink 2 over UDP on 127.0.0.1: it sends
// to the port it is given, as SITL sends to a ground station's 14550, and reads what comes back
// to its own port. Every frame it receives goes through node-mavlink's splitter, which checks its
// checksum; bad ones are counted.
//
//   node emulator.mjs --port PORT [options]
//
//   --firmware px4|ardupilot  HEARTBEAT autopilot (12 or 3) and modes; PX4 takes DO_REPOSITION with
//                           the change-mode bit in any mode (UNSUPPORTED without it) and reads its
//                           altitude above sea level whatever the frame, switching to Hold;
//                           ArduPilot answers DENIED unless in GUIDED (or the bit is set), reads the
//                           altitude in the command's frame; each answers the camera command its
//                           firmware uses (PX4 IMAGE_START_CAPTURE, ArduPilot DO_DIGICAM_CONTROL)
//                           and UNSUPPORTED to the other          (default px4)
//   --home LAT,LON          home, where the vehicle hovers at the start (default 25.2,55.3)
//   --home-amsl M           home's altitude above mean sea level    (default 10)
//   --alt M                 the hover altitude above home at the start (default 20)
//   --heading DEG           the nose's compass heading GLOBAL_POSITION_INT reports (default: unknown,
//                           hdg UINT16_MAX)
//   --speed MPS             horizontal and vertical speed (the timing model's 2 m/s by default)
//   --accel MPS2            acceleration (default 2)
//   --land-speed MPS        descent speed when landing (default 1)
//   --drop P                drop this fraction of the datagrams, both ways (seeded, --seed N)
//   --lose-link-after S     stop sending and receiving S seconds after the start
//   --refuse CMD            answer MAV_RESULT_DENIED to command CMD (repeatable)
//   --stop-short M          stop M metres before every reposition target
//   --no-fix                GPS_RAW_INT fix_type 1 (no fix), no GLOBAL_POSITION_INT
//   --gcs-timeout S         the GCS failsafe: no GCS HEARTBEAT this long, in flight: RTL (default 5)
//   --camera-card DIR       a camera's memory card: DIR/card.csv lists its pictures (file,lat,lon,
//                           each where the camera took it); at every capture the picture nearest the
//                           vehicle is written into --camera-dir as IMG_NNNN and its extension, as a
//                           camera (or its download script) writes its pictures where the live loop
//                           watches (adaptseg_live --camera-folder)
//   --camera-dir DIR        where --camera-card's pictures are written
//   --report FILE           on exit (SIGTERM, SIGINT, --max-time), the counts as JSON
//   --max-time S            exit after S seconds (default 120)
//
// Streams: HEARTBEAT 1 Hz (and a camera component's), GLOBAL_POSITION_INT 4 Hz and GPS_RAW_INT
// 1 Hz until SET_MESSAGE_INTERVAL asks otherwise; the physics runs at 50 Hz.

import dgram from 'node:dgram';
import { copyFileSync, readFileSync, renameSync, writeFileSync } from 'node:fs';
import { extname, join } from 'node:path';
import { minimal, common, MavLinkProtocolV2, MavLinkPacketSplitter, MavLinkPacketParser } from 'node-mavlink';

const REGISTRY = { ...minimal.REGISTRY, ...common.REGISTRY };

// ---------------------------------------------------------------- arguments
function parseArgs(argv) {
  const o = {
    port: 0, firmware: 'px4', home: [25.2, 55.3], homeAmsl: 10, alt: 20, heading: null, speed: 2, accel: 2, landSpeed: 1,
    drop: 0, seed: 1, loseLinkAfter: Infinity, refuse: [], stopShort: 0, noFix: false, gcsTimeout: 5,
    report: null, maxTime: 120, cameraCard: null, cameraDir: null,
  };
  for (let i = 2; i < argv.length; i++) {
    const a = argv[i];
    const next = () => {
      if (i + 1 >= argv.length) throw new Error(`${a} needs a value`);
      return argv[++i];
    };
    const num = () => {
      const v = Number(next());
      if (!Number.isFinite(v)) throw new Error(`${a} needs a number`);
      return v;
    };
    switch (a) {
      case '--port': o.port = num(); break;
      case '--firmware': o.firmware = next(); break;
      case '--home': o.home = next().split(',').map(Number); break;
      case '--home-amsl': o.homeAmsl = num(); break;
      case '--alt': o.alt = num(); break;
      case '--heading': o.heading = num(); break;
      case '--speed': o.speed = num(); break;
      case '--accel': o.accel = num(); break;
      case '--land-speed': o.landSpeed = num(); break;
      case '--drop': o.drop = num(); break;
      case '--seed': o.seed = num(); break;
      case '--lose-link-after': o.loseLinkAfter = num(); break;
      case '--refuse': o.refuse.push(num()); break;
      case '--stop-short': o.stopShort = num(); break;
      case '--no-fix': o.noFix = true; break;
      case '--gcs-timeout': o.gcsTimeout = num(); break;
      case '--report': o.report = next(); break;
      case '--camera-card': o.cameraCard = next(); break;
      case '--camera-dir': o.cameraDir = next(); break;
      case '--max-time': o.maxTime = num(); break;
      default: throw new Error(`unknown option ${a}`);
    }
  }
  if (!(o.port > 0 && o.port < 65536)) throw new Error('--port PORT is required');
  if (o.firmware !== 'px4' && o.firmware !== 'ardupilot') throw new Error('--firmware must be px4 or ardupilot');
  if (o.home.length !== 2 || !o.home.every(Number.isFinite)) throw new Error('--home must be LAT,LON');
  if (o.heading !== null && !(o.heading >= 0 && o.heading < 360)) throw new Error('--heading must be in [0, 360)');
  if ((o.cameraCard === null) !== (o.cameraDir === null)) throw new Error('--camera-card and --camera-dir go together');
  return o;
}

let opt;
try {
  opt = parseArgs(process.argv);
} catch (e) {
  console.error(`emulator: ${e.message}`);
  process.exit(2);
}
const PX4 = opt.firmware === 'px4';

// ---------------------------------------------------------------- constants
const SYSID = 1;
const COMP_AUTOPILOT = 1;
const COMP_CAMERA = 100;
const MAV_TYPE_QUADROTOR = 2;
const MAV_TYPE_CAMERA = 30;
const MAV_AUTOPILOT = PX4 ? 12 : 3;
const MAV_AUTOPILOT_INVALID = 8;
const FLAG_CUSTOM = 1;
const FLAG_ARMED = 128;
const RESULT = { ACCEPTED: 0, TEMPORARILY_REJECTED: 1, DENIED: 2, UNSUPPORTED: 3, FAILED: 4 };
const CMD = {
  RTL: 20, SET_MODE: 176, REPOSITION: 192, DIGICAM: 203, SET_MESSAGE_INTERVAL: 511, IMAGE_START_CAPTURE: 2000,
};
const px4Mode = (main, sub = 0) => ((main << 16) | (sub << 24)) >>> 0;
const MODES = PX4
  ? { start: px4Mode(3), hold: px4Mode(4, 3), rtl: px4Mode(4, 5), land: px4Mode(4, 6) }
  : { start: 5 /* LOITER */, guided: 4, rtl: 6, land: 9 };

// WGS84 metres per degree, the series adaptseg's detail/geodesy.hpp uses.
const RAD = Math.PI / 180;
const mPerDegLat = (lat) => 111132.92 - 559.82 * Math.cos(2 * lat * RAD) + 1.175 * Math.cos(4 * lat * RAD) -
  0.0023 * Math.cos(6 * lat * RAD);
const mPerDegLon = (lat) => 111412.84 * Math.cos(lat * RAD) - 93.5 * Math.cos(3 * lat * RAD) + 0.118 * Math.cos(5 * lat * RAD);

// Seeded generators (mulberry32), one per direction, so that which datagrams a run drops is
// reproducible in each direction: with one generator shared by both, the draws interleaved with
// the timing of the two directions, and a run could drop nothing of what it received (CI:
// dropped_in 0 of 54 at 10 %).
function makeRandom(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6D2B79F5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}
const randomOut = makeRandom(opt.seed);
const randomIn = makeRandom(opt.seed ^ 0x5bd1e995);

// ---------------------------------------------------------------- state
const start = performance.now();
const nowMs = () => performance.now() - start;
const [homeLat, homeLon] = opt.home;
const v = {
  lat: homeLat, lon: homeLon, alt: opt.alt, // alt: above home [m]
  vn: 0, ve: 0, vd: 0, speed: 0,
  armed: true, mode: MODES.start, phase: 'hold', // hold, goto, rtl_return, rtl_land, landed
  goal: null, // {lat, lon, alt}
};
const counts = {
  firmware: opt.firmware, frames_received: 0, bad_crc: 0, unknown_ids: 0, frames_sent: 0, dropped_in: 0,
  dropped_out: 0, ignored_after_link_loss: 0, wrong_target: 0, commands: {}, acks: {}, captures: 0, pictures: [],
  capture_duplicates: 0, repositions: [], modes: [], failsafe: null, lost_link: false,
  gcs: { sysid: null, compid: null, heartbeats: 0, sequence_gaps: 0 },
};
const intervalsMs = { 0: 1000, 33: 250, 24: 1000 };
const nextMs = { 0: 0, 33: 0, 24: 0, camera: 0 };
let lastGcsHeartbeatMs = null;
let lastGcsSeq = null;
let lastCaptureSequence = null;
let imageIndex = 0;

const setMode = (mode) => {
  if (v.mode !== mode) counts.modes.push(mode);
  v.mode = mode;
};
const linkLost = () => {
  const lost = nowMs() >= opt.loseLinkAfter * 1000;
  if (lost) counts.lost_link = true;
  return lost;
};

// ---------------------------------------------------------------- sending
const socket = dgram.createSocket('udp4');
socket.on('error', () => {}); // ICMP errors before the peer listens: nothing to do
const protocols = {
  [COMP_AUTOPILOT]: new MavLinkProtocolV2(SYSID, COMP_AUTOPILOT),
  [COMP_CAMERA]: new MavLinkProtocolV2(SYSID, COMP_CAMERA),
};
const sequences = { [COMP_AUTOPILOT]: 0, [COMP_CAMERA]: 0 };

function send(msg, compid = COMP_AUTOPILOT) {
  if (linkLost()) return;
  const buffer = protocols[compid].serialize(msg, sequences[compid]);
  sequences[compid] = (sequences[compid] + 1) & 0xFF;
  if (opt.drop > 0 && randomOut() < opt.drop) {
    counts.dropped_out += 1;
    return;
  }
  counts.frames_sent += 1;
  socket.send(buffer, opt.port, '127.0.0.1');
}

function heartbeat() {
  const hb = new minimal.Heartbeat();
  hb.type = MAV_TYPE_QUADROTOR;
  hb.autopilot = MAV_AUTOPILOT;
  hb.baseMode = FLAG_CUSTOM | (v.armed ? FLAG_ARMED : 0);
  hb.customMode = v.mode;
  hb.systemStatus = v.armed ? 4 : 3; // ACTIVE, STANDBY
  hb.mavlinkVersion = 3;
  send(hb);
}

function cameraHeartbeat() {
  const hb = new minimal.Heartbeat();
  hb.type = MAV_TYPE_CAMERA;
  hb.autopilot = MAV_AUTOPILOT_INVALID;
  hb.systemStatus = 4;
  hb.mavlinkVersion = 3;
  send(hb, COMP_CAMERA);
}

const e7 = (deg) => Math.round(deg * 1e7);

function globalPosition() {
  if (opt.noFix) return; // no global position without a fix (as PX4)
  const p = new common.GlobalPositionInt();
  p.timeBootMs = Math.round(nowMs()) >>> 0;
  p.lat = e7(v.lat);
  p.lon = e7(v.lon);
  p.alt = Math.round((opt.homeAmsl + v.alt) * 1000);
  p.relativeAlt = Math.round(v.alt * 1000);
  p.vx = Math.round(v.vn * 100);
  p.vy = Math.round(v.ve * 100);
  p.vz = Math.round(v.vd * 100);
  p.hdg = opt.heading === null ? 65535 : Math.round(opt.heading * 100) % 36000;
  send(p);
}

function gpsRaw() {
  const g = new common.GpsRawInt();
  g.timeUsec = BigInt(Math.round(nowMs() * 1000));
  g.fixType = opt.noFix ? 1 : 3;
  g.lat = opt.noFix ? 0 : e7(v.lat);
  g.lon = opt.noFix ? 0 : e7(v.lon);
  g.alt = opt.noFix ? 0 : Math.round((opt.homeAmsl + v.alt) * 1000);
  g.eph = opt.noFix ? 65535 : 80;
  g.epv = opt.noFix ? 65535 : 120;
  g.vel = Math.round(Math.hypot(v.vn, v.ve) * 100);
  g.cog = 65535;
  g.satellitesVisible = opt.noFix ? 0 : 14;
  send(g);
}

function ack(command, result, packet) {
  const a = new common.CommandAck();
  a.command = command;
  a.result = result;
  a.progress = 0;
  a.resultParam2 = 0;
  a.targetSystem = packet.header.sysid;
  a.targetComponent = packet.header.compid;
  counts.acks[result] = (counts.acks[result] || 0) + 1;
  send(a);
}

function statusText(severity, text) {
  const s = new common.StatusText();
  s.severity = severity;
  s.text = text;
  s.id = 0;
  s.chunkSeq = 0;
  send(s);
}

// The memory card of --camera-card: each picture and where it was taken.
const card = opt.cameraCard === null ? [] : readFileSync(join(opt.cameraCard, 'card.csv'), 'utf8').trim().split('\n')
  .slice(1).map((line) => {
    const [file, lat, lon] = line.split(',');
    return { file, lat: Number(lat), lon: Number(lon) };
  });
let pictures = 0;

// A picture taken: the card's nearest the vehicle written into --camera-dir (whole, then renamed,
// as a camera's download lands).
function pictureTaken() {
  if (card.length === 0) return;
  const k = Math.cos((v.lat * Math.PI) / 180);
  const d = (p) => (p.lat - v.lat) ** 2 + ((p.lon - v.lon) * k) ** 2;
  const best = card.reduce((a, b) => (d(b) < d(a) ? b : a));
  const name = `IMG_${String(pictures++).padStart(4, '0')}${extname(best.file)}`;
  copyFileSync(join(opt.cameraCard, best.file), join(opt.cameraDir, `.${name}.part`));
  renameSync(join(opt.cameraDir, `.${name}.part`), join(opt.cameraDir, name));
  counts.pictures.push(best.file);
}

function imageCaptured() {
  const img = new common.CameraImageCaptured();
  img.timeBootMs = Math.round(nowMs()) >>> 0;
  img.timeUtc = BigInt(Date.now()) * 1000n;
  img.cameraId = 0;
  img.lat = e7(v.lat);
  img.lon = e7(v.lon);
  img.alt = Math.round((opt.homeAmsl + v.alt) * 1000);
  img.relativeAlt = Math.round(v.alt * 1000);
  img.q = [1, 0, 0, 0];
  img.imageIndex = imageIndex++;
  img.captureResult = 1;
  img.fileUrl = '';
  send(img, COMP_CAMERA);
}

// ---------------------------------------------------------------- commands
function startRtl() {
  setMode(MODES.rtl);
  v.phase = 'rtl_return';
  v.goal = { lat: homeLat, lon: homeLon, alt: v.alt };
}

// A reposition target, moved --stop-short metres back towards where the vehicle is.
function repositionGoal(lat, lon, alt) {
  if (opt.stopShort <= 0) return { lat, lon, alt };
  const mid = (lat + v.lat) / 2;
  const n = (lat - v.lat) * mPerDegLat(mid);
  const e = (lon - v.lon) * mPerDegLon(mid);
  const h = Math.hypot(n, e);
  if (h <= opt.stopShort) return { lat: v.lat, lon: v.lon, alt };
  const k = (h - opt.stopShort) / h;
  return { lat: v.lat + (n * k) / mPerDegLat(mid), lon: v.lon + (e * k) / mPerDegLon(mid), alt };
}

function onCommand(c, isInt, packet) {
  const command = c.command;
  counts.commands[command] = (counts.commands[command] || 0) + 1;
  if (c.targetSystem !== SYSID && c.targetSystem !== 0) {
    counts.wrong_target += 1;
    return; // not for us: no answer
  }
  if (opt.refuse.includes(command)) {
    if (PX4) statusText(4, 'Reposition command rejected');
    ack(command, RESULT.DENIED, packet);
    return;
  }
  switch (command) {
    case CMD.SET_MESSAGE_INTERVAL: {
      const id = Math.round(c._param1);
      const us = c._param2;
      if (!(id in intervalsMs)) return ack(command, RESULT.UNSUPPORTED, packet);
      if (us === -1) intervalsMs[id] = Infinity;
      else if (us > 0) intervalsMs[id] = us / 1000;
      return ack(command, RESULT.ACCEPTED, packet);
    }
    case CMD.SET_MODE: {
      if ((Math.round(c._param1) & FLAG_CUSTOM) === 0) return ack(command, RESULT.DENIED, packet);
      const mode = PX4 ? px4Mode(Math.round(c._param2), Math.round(c._param3)) : Math.round(c._param2);
      if (!PX4 && ![3, 4, 5, 6, 9].includes(mode)) return ack(command, RESULT.FAILED, packet);
      if (mode === MODES.rtl) startRtl();
      else setMode(mode);
      if (!PX4 && mode === MODES.guided && v.phase !== 'goto') v.phase = 'hold';
      return ack(command, RESULT.ACCEPTED, packet);
    }
    case CMD.REPOSITION: {
      if (!v.armed || v.phase === 'landed') return ack(command, RESULT.DENIED, packet);
      const flags = Math.round(c._param2);
      let lat;
      let lon;
      let alt;
      if (isInt) {
        lat = c._param5 / 1e7;
        lon = c._param6 / 1e7;
      } else if (PX4) {
        lat = c._param5;
        lon = c._param6;
      } else {
        return ack(command, RESULT.UNSUPPORTED, packet); // ArduPilot: DO_REPOSITION as COMMAND_INT only
      }
      if (PX4) {
        // Commander: the change-mode bit and nothing else, or UNSUPPORTED; the navigator reads
        // the altitude above sea level whatever COMMAND_INT's frame says.
        if ((flags & 1) === 0 || (flags & ~1) !== 0) return ack(command, RESULT.UNSUPPORTED, packet);
        alt = c._param7 - opt.homeAmsl;
        setMode(MODES.hold);
      } else {
        if (v.mode !== MODES.guided && (flags & 1) === 0) return ack(command, RESULT.DENIED, packet);
        const frame = isInt ? c.frame : 0;
        if (frame === 0 || frame === 5) alt = c._param7 - opt.homeAmsl; // GLOBAL(_INT): above sea level
        else if (frame === 3 || frame === 6) alt = c._param7; // GLOBAL_RELATIVE_ALT(_INT)
        else return ack(command, RESULT.DENIED, packet);
        setMode(MODES.guided);
      }
      if (!Number.isFinite(lat) || !Number.isFinite(lon) || Math.abs(lat) > 90 || Math.abs(lon) > 180) {
        return ack(command, RESULT.DENIED, packet);
      }
      counts.repositions.push([lat, lon, alt]);
      v.goal = repositionGoal(lat, lon, alt);
      v.phase = 'goto';
      return ack(command, RESULT.ACCEPTED, packet);
    }
    case CMD.IMAGE_START_CAPTURE: {
      if (!PX4) return ack(command, RESULT.UNSUPPORTED, packet);
      if (Math.round(c._param3) !== 1) return ack(command, RESULT.DENIED, packet);
      const sequence = Math.round(c._param4);
      ack(command, RESULT.ACCEPTED, packet);
      if (sequence !== 0 && sequence === lastCaptureSequence) {
        counts.capture_duplicates += 1; // a retransmission: no second image
        return undefined;
      }
      lastCaptureSequence = sequence;
      counts.captures += 1;
      pictureTaken();
      imageCaptured();
      return undefined;
    }
    case CMD.DIGICAM: {
      if (PX4) return ack(command, RESULT.UNSUPPORTED, packet);
      if (Math.round(c._param5) !== 1) return ack(command, RESULT.DENIED, packet);
      counts.captures += 1;
      pictureTaken();
      return ack(command, RESULT.ACCEPTED, packet);
    }
    case CMD.RTL: {
      if (!v.armed) return ack(command, RESULT.DENIED, packet);
      startRtl();
      return ack(command, RESULT.ACCEPTED, packet);
    }
    default:
      return ack(command, RESULT.UNSUPPORTED, packet);
  }
}

// ---------------------------------------------------------------- receiving
const splitter = new MavLinkPacketSplitter({}, { onCrcError: () => { counts.bad_crc += 1; } });
const parser = splitter.pipe(new MavLinkPacketParser());
parser.on('data', (packet) => {
  counts.frames_received += 1;
  const clazz = REGISTRY[packet.header.msgid];
  if (!clazz) return;
  const data = packet.protocol.data(packet.payload, clazz);
  const h = packet.header;
  if (clazz === minimal.Heartbeat && data.type === 6 /* GCS */) {
    counts.gcs.heartbeats += 1;
    counts.gcs.sysid = h.sysid;
    counts.gcs.compid = h.compid;
    lastGcsHeartbeatMs = nowMs();
  }
  if (h.sysid === counts.gcs.sysid) {
    if (lastGcsSeq !== null && h.seq !== ((lastGcsSeq + 1) & 0xFF)) counts.gcs.sequence_gaps += 1;
    lastGcsSeq = h.seq;
  }
  if (clazz === common.CommandLong) onCommand(data, false, packet);
  else if (clazz === common.CommandInt) onCommand(data, true, packet);
});

socket.on('message', (buffer) => {
  if (linkLost()) {
    counts.ignored_after_link_loss += 1;
    return;
  }
  if (opt.drop > 0 && randomIn() < opt.drop) {
    counts.dropped_in += 1;
    return;
  }
  splitter.write(buffer);
});

// ---------------------------------------------------------------- physics
function moveTowards(goal, dt, verticalOnly = false) {
  const mid = (v.lat + goal.lat) / 2;
  const n = verticalOnly ? 0 : (goal.lat - v.lat) * mPerDegLat(mid);
  const e = verticalOnly ? 0 : (goal.lon - v.lon) * mPerDegLon(mid);
  const u = goal.alt - v.alt;
  const d = Math.hypot(n, e, u);
  if (d < 1e-3) {
    v.vn = 0; v.ve = 0; v.vd = 0; v.speed = 0;
    return true;
  }
  const cruise = verticalOnly ? opt.landSpeed : opt.speed;
  v.speed = Math.min(v.speed + opt.accel * dt, cruise, Math.sqrt(2 * opt.accel * d));
  const s = Math.min(v.speed * dt, d);
  v.lat += (n / d) * s / mPerDegLat(mid);
  v.lon += (e / d) * s / mPerDegLon(mid);
  v.alt += (u / d) * s;
  v.vn = (n / d) * v.speed;
  v.ve = (e / d) * v.speed;
  v.vd = -(u / d) * v.speed;
  if (s >= d) {
    v.speed = 0;
    return true;
  }
  return false;
}

let lastTickMs = nowMs();
function tick() {
  const t = nowMs();
  const dt = (t - lastTickMs) / 1000;
  lastTickMs = t;
  if (v.armed) {
    if (v.phase === 'goto' && v.goal) {
      if (moveTowards(v.goal, dt)) v.phase = 'hold';
    } else if (v.phase === 'rtl_return') {
      if (moveTowards(v.goal, dt)) {
        v.phase = 'rtl_land';
        if (PX4) setMode(MODES.rtl); // PX4's Return lands itself; ArduPilot's RTL too
      }
    } else if (v.phase === 'rtl_land') {
      if (moveTowards({ lat: homeLat, lon: homeLon, alt: 0 }, dt, true)) {
        v.phase = 'landed';
        v.armed = false;
        v.alt = 0;
      }
    } else {
      v.vn = 0; v.ve = 0; v.vd = 0; v.speed = 0;
    }
    // The GCS failsafe: the ground station's heartbeat lost while flying under its control.
    const underGcs = PX4 ? v.mode === MODES.hold : v.mode === MODES.guided;
    if (underGcs && lastGcsHeartbeatMs !== null && t - lastGcsHeartbeatMs > opt.gcsTimeout * 1000) {
      counts.failsafe = 'gcs_lost_rtl';
      startRtl();
    }
  }
  for (const id of ['0', '33', '24']) {
    if (t >= nextMs[id]) {
      if (id === '0') heartbeat();
      else if (id === '33') globalPosition();
      else gpsRaw();
      nextMs[id] = Math.max(nextMs[id] + intervalsMs[id], t - 1);
    }
  }
  if (t >= nextMs.camera) {
    cameraHeartbeat();
    nextMs.camera = t + 1000;
  }
}

// ---------------------------------------------------------------- run and report
function report() {
  counts.bad_crc = Math.max(counts.bad_crc, splitter.invalidPackages);
  counts.unknown_ids = splitter.unknownPackagesCount;
  counts.final = { lat: v.lat, lon: v.lon, alt: v.alt, armed: v.armed, phase: v.phase, mode: v.mode };
  counts.landed = v.phase === 'landed';
  counts.elapsed_s = nowMs() / 1000;
  if (opt.report) writeFileSync(opt.report, `${JSON.stringify(counts, null, 1)}\n`);
}

let finished = false;
function finish() {
  if (finished) return;
  finished = true;
  report();
  socket.close();
  process.exit(0);
}
process.on('SIGTERM', finish);
process.on('SIGINT', finish);

socket.bind(0, '127.0.0.1', () => {
  console.log(`emulator: ${PX4 ? 'PX4' : 'ArduPilot'} on 127.0.0.1:${socket.address().port}, sending to ` +
              `127.0.0.1:${opt.port}`);
  setInterval(tick, 20);
  setTimeout(finish, opt.maxTime * 1000);
});

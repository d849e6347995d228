// Independent check of fact-fc-bridge's bytes with node-mavlink 2.3.0 (not our decoder):
//   node mavlink_decode.js FILE [--expect-commands]
// FILE holds the raw bytes the bridge sent (its --dump, or a UDP capture) while
// fact_fc_bridge_peer drove it (see test/fc_bridge_peer.cpp for the published values). Checks:
// every frame passes node-mavlink's CRC (with CRC_EXTRA), header ids and consecutive sequence
// numbers, and EVERY field of every HEARTBEAT, SET_POSITION_TARGET_LOCAL_NED, ODOMETRY and
// COMMAND_LONG against values recomputed here from the peer's inputs (FLU -> NED applied with
// rotation matrices written here); then that a frame with one flipped byte is a CRC error.
// Exit 0 when all checks pass, 1 otherwise.
'use strict';
const fs = require('fs');
const { Readable } = require('stream');
const { MavLinkPacketSplitter, MavLinkPacketParser, minimal, common } = require('node-mavlink');

const file = process.argv[2];
const expectCommands = process.argv.includes('--expect-commands');
const REGISTRY = { ...minimal.REGISTRY, ...common.REGISTRY };
let failures = 0;
const fail = (msg) => { if (failures < 40) console.error('FAIL: ' + msg); failures++; };
const f32 = Math.fround;
function near(what, got, want, tol = 1e-6) {
  if (Number.isNaN(want)) { if (!Number.isNaN(got)) fail(`${what}: got ${got}, want NaN`); return; }
  if (typeof got !== 'number' || Math.abs(got - f32(want)) > tol * Math.max(1, Math.abs(want)))
    fail(`${what}: got ${got}, want ${want}`);
}
function equal(what, got, want) { if (got !== want) fail(`${what}: got ${got}, want ${want}`); }

// --- the expected values, recomputed from the peer's inputs -----------------------------------
// f_i is ENU-like; NED = (y, x, -z); body FLU -> FRD = diag(1, -1, -1).
const NED_ENU = [[0, 1, 0], [1, 0, 0], [0, 0, -1]];
const FLU_FRD = [[1, 0, 0], [0, -1, 0], [0, 0, -1]];
const mul = (A, B) => A.map((r) => [0, 1, 2].map((j) => r[0] * B[0][j] + r[1] * B[1][j] + r[2] * B[2][j]));
const mulv = (A, v) => A.map((r) => r[0] * v[0] + r[1] * v[1] + r[2] * v[2]);
const T = (A) => [0, 1, 2].map((i) => [0, 1, 2].map((j) => A[j][i]));
const Rx = (a) => [[1, 0, 0], [0, Math.cos(a), -Math.sin(a)], [0, Math.sin(a), Math.cos(a)]];
const Ry = (a) => [[Math.cos(a), 0, Math.sin(a)], [0, 1, 0], [-Math.sin(a), 0, Math.cos(a)]];
const Rz = (a) => [[Math.cos(a), -Math.sin(a), 0], [Math.sin(a), Math.cos(a), 0], [0, 0, 1]];
function quatFromMatrix(R) {  // w, x, y, z with w >= 0 (Shepperd's method)
  const tr = R[0][0] + R[1][1] + R[2][2];
  let q;
  if (tr > 0) {
    const s = Math.sqrt(tr + 1) * 2;
    q = [s / 4, (R[2][1] - R[1][2]) / s, (R[0][2] - R[2][0]) / s, (R[1][0] - R[0][1]) / s];
  } else if (R[0][0] > R[1][1] && R[0][0] > R[2][2]) {
    const s = Math.sqrt(1 + R[0][0] - R[1][1] - R[2][2]) * 2;
    q = [(R[2][1] - R[1][2]) / s, s / 4, (R[0][1] + R[1][0]) / s, (R[0][2] + R[2][0]) / s];
  } else if (R[1][1] > R[2][2]) {
    const s = Math.sqrt(1 + R[1][1] - R[0][0] - R[2][2]) * 2;
    q = [(R[0][2] - R[2][0]) / s, (R[0][1] + R[1][0]) / s, s / 4, (R[1][2] + R[2][1]) / s];
  } else {
    const s = Math.sqrt(1 + R[2][2] - R[0][0] - R[1][1]) * 2;
    q = [(R[1][0] - R[0][1]) / s, (R[0][2] + R[2][0]) / s, (R[1][2] + R[2][1]) / s, s / 4];
  }
  return q[0] < 0 ? q.map((x) => -x) : q;
}
const wrap = (a) => { while (a > Math.PI) a -= 2 * Math.PI; while (a <= -Math.PI) a += 2 * Math.PI; return a; };

const SETPOINT = { p: [1, 2, 3], v: [0.5, -0.25, 0.1], a: [0.1, 0.2, -0.3], yaw: 0.3, yawRate: 0.1 };
const toNed = (v) => mulv(NED_ENU, v);

function checkHeartbeat(m, i) {
  equal(`HEARTBEAT[${i}].type (ONBOARD_CONTROLLER)`, m.type, 18);
  equal(`HEARTBEAT[${i}].autopilot (INVALID)`, m.autopilot, 8);
  equal(`HEARTBEAT[${i}].baseMode`, m.baseMode, 0);
  equal(`HEARTBEAT[${i}].customMode`, m.customMode, 0);
  equal(`HEARTBEAT[${i}].systemStatus (ACTIVE)`, m.systemStatus, 4);
  equal(`HEARTBEAT[${i}].mavlinkVersion`, m.mavlinkVersion, 3);
}

let lastBootMs = -1;
function checkSetpoint(m, i) {
  const p = toNed(SETPOINT.p), v = toNed(SETPOINT.v), a = toNed(SETPOINT.a);
  if (typeof m.timeBootMs !== 'number' || m.timeBootMs < lastBootMs) fail(`SPT[${i}].timeBootMs ${m.timeBootMs} went back`);
  lastBootMs = m.timeBootMs;
  near(`SPT[${i}].x`, m.x, p[0]); near(`SPT[${i}].y`, m.y, p[1]); near(`SPT[${i}].z`, m.z, p[2]);
  near(`SPT[${i}].vx`, m.vx, v[0]); near(`SPT[${i}].vy`, m.vy, v[1]); near(`SPT[${i}].vz`, m.vz, v[2]);
  near(`SPT[${i}].afx`, m.afx, a[0]); near(`SPT[${i}].afy`, m.afy, a[1]); near(`SPT[${i}].afz`, m.afz, a[2]);
  near(`SPT[${i}].yaw`, m.yaw, wrap(Math.PI / 2 - SETPOINT.yaw));
  near(`SPT[${i}].yawRate`, m.yawRate, -SETPOINT.yawRate);
  equal(`SPT[${i}].typeMask`, m.typeMask, 0);
  equal(`SPT[${i}].targetSystem`, m.targetSystem, 1);
  equal(`SPT[${i}].targetComponent`, m.targetComponent, 1);
  equal(`SPT[${i}].coordinateFrame (LOCAL_NED)`, m.coordinateFrame, 1);
}

const resetCounters = new Set();
function checkOdometry(m, i) {
  const k = Number((BigInt(m.timeUsec) - 1000000000n) / 10000n);
  if (!(k >= 0) || BigInt(m.timeUsec) !== 1000000000n + 10000n * BigInt(k)) { fail(`ODOMETRY[${i}].timeUsec ${m.timeUsec}`); return; }
  const pos = toNed([0.01 * k, 1 - 0.02 * k, 1.5]);
  const yaw = 0.2 + 0.001 * k, roll = 0.05, pitch = -0.03;
  const R = mul(mul(NED_ENU, mul(Rz(yaw), mul(Ry(pitch), Rx(roll)))), FLU_FRD);  // body FRD -> NED
  const q = quatFromMatrix(R);
  const vBody = mulv(T(R), toNed([0.3, -0.2, 0.05]));
  near(`ODOMETRY[${i}].x`, m.x, pos[0]); near(`ODOMETRY[${i}].y`, m.y, pos[1]); near(`ODOMETRY[${i}].z`, m.z, pos[2]);
  for (let j = 0; j < 4; j++) near(`ODOMETRY[${i}].q[${j}]`, m.q[j], q[j]);
  near(`ODOMETRY[${i}].vx`, m.vx, vBody[0]); near(`ODOMETRY[${i}].vy`, m.vy, vBody[1]); near(`ODOMETRY[${i}].vz`, m.vz, vBody[2]);
  near(`ODOMETRY[${i}].rollspeed`, m.rollspeed, NaN);
  near(`ODOMETRY[${i}].pitchspeed`, m.pitchspeed, NaN);
  near(`ODOMETRY[${i}].yawspeed`, m.yawspeed, NaN);
  for (const name of ['poseCovariance', 'velocityCovariance']) {
    equal(`ODOMETRY[${i}].${name}.length`, m[name].length, 21);
    near(`ODOMETRY[${i}].${name}[0]`, m[name][0], NaN);
    for (let j = 1; j < 21; j++) near(`ODOMETRY[${i}].${name}[${j}]`, m[name][j], 0);
  }
  equal(`ODOMETRY[${i}].frameId (LOCAL_NED)`, m.frameId, 1);
  equal(`ODOMETRY[${i}].childFrameId (BODY_FRD)`, m.childFrameId, 12);
  equal(`ODOMETRY[${i}].resetCounter (k=${k})`, m.resetCounter, k >= 100 ? 1 : 0);
  equal(`ODOMETRY[${i}].estimatorType (VIO)`, m.estimatorType, 3);
  equal(`ODOMETRY[${i}].quality`, m.quality, 0);
  resetCounters.add(m.resetCounter);
}

const commands = { 176: [], 400: [] };
function checkCommand(m, i) {
  const p = [m._param1, m._param2, m._param3, m._param4, m._param5, m._param6, m._param7];
  if (m.command === 176) {  // MAV_CMD_DO_SET_MODE: custom mode enabled, PX4 main mode OFFBOARD
    near(`COMMAND_LONG[${i}] DO_SET_MODE param1`, p[0], 1); near(`COMMAND_LONG[${i}] DO_SET_MODE param2`, p[1], 6);
  } else if (m.command === 400) {  // MAV_CMD_COMPONENT_ARM_DISARM: arm
    near(`COMMAND_LONG[${i}] ARM param1`, p[0], 1); near(`COMMAND_LONG[${i}] ARM param2`, p[1], 0);
  } else { fail(`COMMAND_LONG[${i}].command ${m.command} unexpected`); return; }
  for (let j = 2; j < 7; j++) near(`COMMAND_LONG[${i}].param${j + 1}`, p[j], 0);
  equal(`COMMAND_LONG[${i}].targetSystem`, m.targetSystem, 1);
  equal(`COMMAND_LONG[${i}].targetComponent`, m.targetComponent, 1);
  equal(`COMMAND_LONG[${i}].confirmation (retry index)`, m.confirmation, commands[m.command].length);
  commands[m.command].push(m);
}

// --- decoding --------------------------------------------------------------------------------
function decodeAll(bytes) {
  return new Promise((resolve) => {
    const crcErrors = [];
    const packets = [];
    const splitter = new MavLinkPacketSplitter({}, { onCrcError: (b) => crcErrors.push(b) });
    const parser = new MavLinkPacketParser();
    Readable.from([bytes]).pipe(splitter).pipe(parser);
    parser.on('data', (p) => packets.push(p));
    parser.on('end', () => resolve({ packets, crcErrors, splitter }));
  });
}

async function main() {
  const bytes = fs.readFileSync(file);
  const { packets, crcErrors, splitter } = await decodeAll(bytes);
  equal('CRC errors in the bridge output', crcErrors.length, 0);
  equal('unknown packets', splitter.unknownPackagesCount ?? 0, 0);
  const counts = {};
  let seq = null, total = 0;
  for (const p of packets) {
    total += p.buffer.length;
    equal('magic (MAVLink v2)', p.header.magic, 0xfd);
    equal(`sysid of msgid ${p.header.msgid}`, p.header.sysid, 1);
    equal(`compid of msgid ${p.header.msgid}`, p.header.compid, 191);
    if (seq !== null) equal('seq (consecutive)', p.header.seq, (seq + 1) % 256);
    seq = p.header.seq;
    const clazz = REGISTRY[p.header.msgid];
    if (!clazz) { fail(`unknown msgid ${p.header.msgid}`); continue; }
    const m = p.protocol.data(p.payload, clazz);
    const name = clazz.MSG_NAME;
    const i = counts[name] = (counts[name] || 0) + 1;
    if (name === 'HEARTBEAT') checkHeartbeat(m, i);
    else if (name === 'SET_POSITION_TARGET_LOCAL_NED') checkSetpoint(m, i);
    else if (name === 'ODOMETRY') checkOdometry(m, i);
    else if (name === 'COMMAND_LONG') checkCommand(m, i);
    else fail(`unexpected message ${name}`);
  }
  equal('bytes decoded (no garbage between frames)', total, bytes.length);
  for (const name of ['HEARTBEAT', 'SET_POSITION_TARGET_LOCAL_NED', 'ODOMETRY'])
    if (!counts[name]) fail(`no ${name} decoded`);
  if (!resetCounters.has(0) || !resetCounters.has(1)) fail(`reset_counter values seen: ${[...resetCounters]} (want 0 and 1)`);
  if (expectCommands) {
    if (!commands[176].length) fail('no COMMAND_LONG DO_SET_MODE (176)');
    if (!commands[400].length) fail('no COMMAND_LONG COMPONENT_ARM_DISARM (400)');
  } else if (counts.COMMAND_LONG) fail('COMMAND_LONG sent without --arm / --offboard');

  // One flipped byte in a frame: node-mavlink must report a CRC error and decode nothing.
  for (const name of ['SET_POSITION_TARGET_LOCAL_NED', 'ODOMETRY', 'HEARTBEAT']) {
    const p = packets.find((x) => REGISTRY[x.header.msgid]?.MSG_NAME === name);
    if (!p) continue;
    const bad = Buffer.from(p.buffer);
    bad[10 + Math.floor(p.header.payloadLength / 2)] ^= 0x01;  // a payload byte
    const r = await decodeAll(bad);
    equal(`${name} with a flipped byte: CRC errors`, r.crcErrors.length, 1);
    equal(`${name} with a flipped byte: packets decoded`, r.packets.length, 0);
  }
  console.log(`node-mavlink ${require('node-mavlink/package.json').version}: ${packets.length} frames, ` +
    Object.entries(counts).map(([k, v]) => `${k} ${v}`).join(', ') +
    `; COMMAND_LONG DO_SET_MODE ${commands[176].length}, ARM ${commands[400].length}`);
  if (failures) { console.error(`${failures} check(s) failed`); process.exit(1); }
  console.log('all checks passed');
}
main().catch((e) => { console.error(e); process.exit(1); });

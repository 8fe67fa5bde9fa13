// Loads build/wasm/pocketbot.wasm the way the emulator does and checks the sim_abi.h contract:
// exactly the declared exports and no imports, hello at reset, state packets, IR beacons, motor outputs.
'use strict';
const fs = require('fs');
const path = process.argv[2];
const mod = new WebAssembly.Module(fs.readFileSync(path));
let failures = 0;
function check(cond, msg) { if (!cond) { failures++; console.log('FAIL wasm: ' + msg); } }

// Offsets come from the layout the protocol generator wrote (protocol/golden/layout.txt), not from here.
const layout = {};
let struct = null;
for (const line of fs.readFileSync(require('path').join(__dirname, '../../protocol/golden/layout.txt'), 'utf8').split('\n')) {
  const w = line.trim().split(' ');
  if (line.startsWith('struct ')) { struct = w[1]; layout[struct] = { size: +w[2], fields: {} }; }
  else if (line.startsWith(' ') && struct) layout[struct].fields[w[0]] = +w[2];
  else struct = null;
}
const STATE_SIZE = layout.robot_state.size, SETTINGS_SIZE = layout.settings.size;
const BATTERY = layout.robot_state.fields.power + layout.state_power.fields.battery_mv;

const exportsWanted = ['memory', 'sim_init', 'sim_advance', 'sim_encoder_edge', 'sim_uart_rx', 'sim_uart_tx_take',
  'sim_uart_tx_buffer', 'sim_ir_rx', 'sim_outputs', 'sim_state', 'sim_settings', 'sim_eeprom', 'sim_events',
  'sim_run_events', 'sim_inputs', 'sim_ir_out'];
const exportsHave = WebAssembly.Module.exports(mod).map(e => e.name).sort();
check(JSON.stringify(exportsHave) === JSON.stringify(exportsWanted.slice().sort()), 'exports ' + exportsHave);
const importsHave = WebAssembly.Module.imports(mod).map(i => i.module + '.' + i.name);
check(importsHave.length === 0, 'no imports (sensors and IR are data): ' + importsHave);

const x = new WebAssembly.Instance(mod, {}).exports;
check(new Uint8Array(x.memory.buffer, x.sim_eeprom(), 2048).every(b => b === 0xff), 'a fresh EEPROM is erased');
// sim_inputs_t: no noise, ambient 300, white floor, the sensors' values at offset 112 (battery first).
const inputs = new DataView(x.memory.buffer, x.sim_inputs(), 192);
inputs.setFloat64(16, 300, true);
inputs.setFloat64(24, 100, true);
inputs.setFloat64(32, 1800, true);
for (let s = 0; s < 10; s++) inputs.setFloat64(112 + 8 * s, s === 0 ? 3700 : 100, true);
x.sim_init(7);
const bytes = [];
const ir = [];
const TICKS_PER_MS = 32000n;
for (let ms = 1n; ms <= 250n; ms++) {
  x.sim_advance(ms * TICKS_PER_MS);
  const n = x.sim_uart_tx_take(64);
  bytes.push(...new Uint8Array(x.memory.buffer, x.sim_uart_tx_buffer(), n));
  const out = new DataView(x.memory.buffer, x.sim_ir_out(), 8 + 24 * 32); // sim_ir_out_t, emptied every step
  for (let i = 0; i < out.getInt32(0, true); i++) ir.push([out.getInt32(8 + 24 * i, true)]);
  out.setInt32(0, 0, true);
}
const frames = [];
let cur = [];
for (const b of bytes) { if (b === 0xc0) { if (cur.length) frames.push(cur); cur = []; } else cur.push(b); }
check(frames.length >= 3 && frames[0][0] === 0x01, 'hello first, then state: ' + frames.map(f => f[0]));
check(String.fromCharCode(...frames[0].slice(4, 15)) === 'PocketBot-7', 'name of robot 7');
check(frames.filter(f => f[0] === 0x02).length === 2, 'two full state packets in 250 ms');
const state = new DataView(x.memory.buffer, x.sim_state(), STATE_SIZE);
check(state.getUint32(0, true) === 250, 'time_ms ' + state.getUint32(0, true));
check(state.getUint16(BATTERY, true) === 3700, 'battery in the state');
check(ir.length >= 20 && ir.every(m => m[0] === 7), 'IR beacons from robot 7: ' + ir.length);
const settings = new DataView(x.memory.buffer, x.sim_settings(), SETTINGS_SIZE);
check(settings.getUint8(0) === 7, 'settings.identity.robot_id');
// Teleoperation: wheel_speeds 0.1 / 0.1 m/s -> positive PWM on both motors.
const frame = [0x24, 0, 8];
const p = new DataView(new ArrayBuffer(8)); p.setFloat32(0, 0.1, true); p.setFloat32(4, 0.1, true);
frame.push(...new Uint8Array(p.buffer));
let crc = 0xffff;
for (const b of frame) { crc ^= b << 8; for (let i = 0; i < 8; i++) crc = (crc & 0x8000) ? ((crc << 1) ^ 0x1021) & 0xffff : (crc << 1) & 0xffff; }
frame.push(crc & 0xff, crc >> 8);
// Delivered as one batch of events (sim_run_events), a byte every 100 us, then on to 260 ms.
const wire = [0xc0, ...frame, 0xc0];
const events = new DataView(x.memory.buffer, x.sim_events(), 16 * wire.length);
wire.forEach((b, i) => {
  events.setBigInt64(16 * i, 250n * TICKS_PER_MS + BigInt(i + 1) * 3200n, true);
  events.setInt32(16 * i + 8, 0, true); // SIM_EVENT_UART_RX
  events.setInt32(16 * i + 12, b, true);
});
x.sim_run_events(wire.length, 260n * TICKS_PER_MS);
const out = new DataView(x.memory.buffer, x.sim_outputs(), 6);
check(out.getInt16(0, true) > 0 && out.getInt16(2, true) > 0, 'motors driven: ' + out.getInt16(0, true));
console.log(failures ? `wasm contract: ${failures} failed` : 'wasm contract: exports and behaviour as in sim_abi.h');
process.exit(failures ? 1 : 0);

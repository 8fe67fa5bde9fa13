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
  'sim_run_events', 'sim_inputs', 'sim_ir_out', 'sim_links', 'sim_link_tx_take'];
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
// A frame (type, seq, payload bytes) with its CRC, SLIP-framed (no byte here needs escaping).
function wire(type, seq, payload) {
  const frame = [type, seq, payload.length, ...payload];
  let crc = 0xffff;
  for (const b of frame) { crc ^= b << 8; for (let i = 0; i < 8; i++) crc = (crc & 0x8000) ? ((crc << 1) ^ 0x1021) & 0xffff : (crc << 1) & 0xffff; }
  return [0xc0, ...frame, crc & 0xff, crc >> 8, 0xc0];
}
const le = (n, size) => Array.from({ length: size }, (_, i) => Number((BigInt(n) >> BigInt(8 * i)) & 0xffn));
const label = s => [...Buffer.from(s.padEnd(16, '\0'))];
const p = new DataView(new ArrayBuffer(8)); p.setFloat32(0, 0.1, true); p.setFloat32(4, 0.1, true);
// Events (sim_run_events) from 250 ms on, one every 100 us: kind 0 a UART byte, 2 a byte on a link, 3 a link opens.
let at = 250n * TICKS_PER_MS;
function deliver(list, until) {
  const events = new DataView(x.memory.buffer, x.sim_events(), 16 * list.length);
  list.forEach(([kind, arg], i) => {
    at += 3200n;
    events.setBigInt64(16 * i, at, true);
    events.setInt32(16 * i + 8, kind, true);
    events.setInt32(16 * i + 12, arg, true);
  });
  x.sim_run_events(list.length, until);
}
check(x.sim_links() >= 2, 'host links: ' + x.sim_links());
// The host on the UART drives (hello_request, set_role), then teleoperation: positive PWM on both motors.
const driver = [...wire(0x10, 1, [...le(3, 2), ...le(0x1234, 4)]), ...wire(0x17, 2, [1, ...label('smoke@js')]),
  ...wire(0x24, 0, [...new Uint8Array(p.buffer)])];
for (let i = 0; i < driver.length; i += 64) deliver(driver.slice(i, i + 64).map(b => [0, b]), -1n);
x.sim_advance(at + 5n * TICKS_PER_MS);
const out = new DataView(x.memory.buffer, x.sim_outputs(), 6);
check(out.getInt16(0, true) > 0 && out.getInt16(2, true) > 0, 'motors driven: ' + out.getInt16(0, true));
// A second host on link 1 watches: its wheel_speeds is refused (error not_driver on link 1).
deliver([[3, 1], ...wire(0x24, 0, [0, 0, 0, 0, 0, 0, 0, 0]).map(b => [2, 1 << 8 | b])], at + 10n * TICKS_PER_MS);
const reply = new Uint8Array(x.memory.buffer, x.sim_uart_tx_buffer(), x.sim_link_tx_take(1, 256));
const error = [...reply].join(',').includes([0xc0, 0x05].join(','));
check(error && out.getInt16(0, true) > 0, 'the watcher refused, the driver still drives: ' + [...reply]);
console.log(failures ? `wasm contract: ${failures} failed` : 'wasm contract: exports and behaviour as in sim_abi.h');
process.exit(failures ? 1 : 0);

#!/usr/bin/env python3
"""The firmware's Bluetooth stack against Bumble's virtual controllers, end to end.

    bt_e2e.py ROBOT_PROGRAM [--trace FILE]
    bt_e2e.py --firmware BT_ROBOT_PROGRAM

Starts two virtual BR/EDR controllers on one Bumble LocalLink: the robot's, reached as an H4 byte stream on a
loopback TCP port (port 0: the system picks one), and a peer's, driven by a Bumble host in this process. It runs
ROBOT_PROGRAM --live PORT SECONDS (tests/bt_wire.c: the stack, echoing what its data channels receive), then, as a
phone or computer would: pages the robot by address, pairs (Secure Simple Pairing, just works), finds the Serial
Port and the framed service by SDP, opens RFCOMM (credits) and writes to it, opens the framed L2CAP channel and
sends SDUs, with two peers at once; every echo must come back whole. --trace writes the H4 bytes of the robot's
wire with their direction and time (the source of tests/bt_traces.h). Exit status 0 when every check held.
"""
import argparse
import asyncio
import pathlib
import re
import struct
import subprocess
import sys
import time

from bumble import core, hci, l2cap, rfcomm, sdp
from bumble.controller import Controller
from bumble.device import Device
from bumble.link import LocalLink
from bumble.transport.common import PacketParser

ROBOT_ADDRESS = "0A:0B:0C:0D:0E:0F"
PSM_FRAMED = 0x1001  # firmware/bluetooth/bt_config.h
FRAMED_UUID = core.UUID("6e2a6f10-5b1e-4c3a-9a4e-70b0c4e7b001")
SPP_UUID = core.UUID.from_16_bits(0x1101)


class RobotController(Controller):
    """Bumble's controller, answering Read_Scan_Enable (the robot's keep-alive) as a real one does: Bumble knows no
    class for it, so the command arrives generic and would go unanswered."""

    def on_hci_read_scan_enable_command(self, command):
        scans = bytes([hci.HCI_SUCCESS, self.classic_scan_enable])
        self.send_hci_packet(hci.HCI_Command_Complete_Event(
            num_hci_command_packets=1, command_opcode=command.op_code,
            return_parameters=hci.HCI_GenericReturnParameters(data=scans)))


class RobotWire(asyncio.Protocol):
    """The robot's controller on the far side of a TCP connection carrying H4, with an optional trace."""

    def __init__(self, controller, trace):
        self.controller = controller
        self.trace = trace
        self.transport = None
        self.parser = PacketParser(ControllerSink(controller))
        self.t0 = time.monotonic()

    def record(self, direction, data):
        if self.trace is not None:
            self.trace.append((time.monotonic() - self.t0, direction, bytes(data)))

    def connection_made(self, transport):
        self.t0 = time.monotonic()  # the robot's clock starts about now
        self.transport = transport
        self.controller.host = self

    def data_received(self, data):  # robot to controller
        self.record(">", data)
        try:
            self.parser.feed_data(data)
        except Exception as e:  # a garbled packet type: the parser starts over, as a controller's would
            print(f"robot wire: {e}")

    def on_packet(self, packet):  # controller to robot
        if self.transport is not None:
            self.record("<", packet)
            self.transport.write(packet)


class ControllerSink:
    def __init__(self, controller):
        self.controller = controller

    def on_packet(self, packet):
        self.controller.on_packet(packet)


async def wait_for(predicate, timeout, what):
    end = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > end:
            raise TimeoutError(what)
        await asyncio.sleep(0.01)


async def peer_session(device, name, payload_rounds):
    """One host: connect, pair, SDP, RFCOMM echo, framed L2CAP echo. Returns the number of checks that held."""
    conn = await device.connect(ROBOT_ADDRESS, transport=core.PhysicalTransport.BR_EDR)
    await conn.authenticate()
    channel = await rfcomm.find_rfcomm_channel_with_uuid(conn, SPP_UUID)
    assert channel == 1, f"{name}: SPP on RFCOMM channel {channel}"
    async with sdp.Client(conn) as client:
        found = await client.search_attributes([FRAMED_UUID], [(0x0000, 0xFFFF)])
    assert len(found) == 1, f"{name}: framed service records {found}"
    attrs = {a.id: a.value for a in found[0]}
    psm = attrs[sdp.SDP_PROTOCOL_DESCRIPTOR_LIST_ATTRIBUTE_ID].value[0].value[1].value
    assert psm == PSM_FRAMED, f"{name}: framed PSM {psm:#x}"

    mux = await rfcomm.Client(conn).start()
    dlc = await mux.open_dlc(channel)
    received = bytearray()
    dlc.sink = received.extend
    sent = bytearray()
    for i in range(payload_rounds):  # request and answer, as a host and the robot talk
        chunk = bytes((i * 7 + k) & 0xFF for k in range(60 + i))
        dlc.write(chunk)
        sent.extend(chunk)
        await wait_for(lambda: len(received) >= len(sent), 10, f"{name}: RFCOMM echo {len(received)}/{len(sent)}")
    assert bytes(received) == bytes(sent), f"{name}: RFCOMM echo differs"

    # One data channel per link: the framed service on its own connection is tried after RFCOMM closes.
    await dlc.disconnect()
    await mux.disconnect()
    l2 = await conn.create_l2cap_channel(spec=l2cap.ClassicChannelSpec(psm=PSM_FRAMED, mtu=200))
    sdus = []
    l2.sink = sdus.append
    expected = []
    for i in range(payload_rounds):
        sdu = bytes((i + k) & 0xFF for k in range(100 + (i % 25)))
        l2.write(sdu)
        expected.append(sdu)
        await wait_for(lambda: len(sdus) >= len(expected), 10, f"{name}: framed echo {len(sdus)}/{len(expected)}")
    assert sdus == expected, f"{name}: framed echo differs"
    await l2.disconnect()
    await conn.disconnect()
    return True


def h4_packets(data):
    """Splits an H4 byte stream into packets."""
    out, i = [], 0
    while i < len(data):
        kind = data[i]
        if kind == 0x04:
            n = 3 + data[i + 2]
        elif kind == 0x02:
            n = 5 + (data[i + 3] | data[i + 4] << 8)
        else:
            n = 4 + data[i + 3]
        out.append(data[i:i + n])
        i += n
    return out


def write_trace_c(path, trace):
    """The controller's packets to the robot, in order, with the robot's answers on SDP (for tests/test_bt_*.c)."""
    to_robot = [(t, p) for t, direction, d in trace if direction == "<" for p in h4_packets(d)]
    from_robot = h4_packets(b"".join(d for _, direction, d in trace if direction == ">"))
    lines = ["/* GENERATED by tests/bt_e2e.py --trace-c: a recorded session of the stack with Bumble 0.0.236 (one peer",
             " * pages the robot, pairs, reads SDP, echoes 3 writes over RFCOMM and 3 SDUs over the framed channel). */",
             "#ifndef BT_TRACE_H", "#define BT_TRACE_H", "", "#include <stdint.h>", "",
             "/* Controller to robot: each H4 packet after the robot time it was sent at (ms) and its length (16 bits",
             " * each). */",
             f"static const uint8_t bt_trace_in[] = {{"]
    for t, p in to_robot:
        ms = int(t * 1000)
        lines.append("    " + ", ".join(f"0x{b:02X}" for b in [ms & 0xFF, ms >> 8, len(p) & 0xFF, len(p) >> 8]
                                        + list(p)) + ",")
    lines += ["};", f"#define BT_TRACE_IN_COUNT {len(to_robot)}", "",
              "/* Robot to controller, the same way. */", "static const uint8_t bt_trace_out[] = {"]
    for p in from_robot:
        lines.append("    " + ", ".join(f"0x{b:02X}" for b in [len(p) & 0xFF, len(p) >> 8] + list(p)) + ",")
    lines += ["};", f"#define BT_TRACE_OUT_COUNT {len(from_robot)}", "", "#endif", ""]
    with open(path, "w") as f:
        f.write("\n".join(lines))


# ---- the PocketBot protocol, as much as the check needs ----

PKT_HELLO, PKT_STATE_FULL, PKT_HELLO_REQUEST = 0x01, 0x02, 0x10
SLIP_END, SLIP_ESC = 0xC0, 0xDB


def protocol_version():
    header = pathlib.Path(__file__).resolve().parent.parent / "protocol" / "pb_protocol.h"
    return int(re.search(r"#define PB_PROTOCOL_VERSION (\d+)", header.read_text()).group(1))


def crc16(data):
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def frame(kind, seq, payload):
    body = bytes([kind, seq, len(payload)]) + payload
    return body + struct.pack("<H", crc16(body))


def slip(data):
    out = bytearray([SLIP_END])
    for b in data:
        out += bytes([SLIP_ESC, 0xDC]) if b == SLIP_END else bytes([SLIP_ESC, 0xDD]) if b == SLIP_ESC else bytes([b])
    out.append(SLIP_END)
    return bytes(out)


class SlipFrames:
    """Frames out of a SLIP byte stream, each checked."""

    def __init__(self):
        self.buf, self.frames = bytearray(), []

    def feed(self, data):
        for b in data:
            if b != SLIP_END:
                self.buf.append(b)
                continue
            raw = bytes(self.buf).replace(bytes([SLIP_ESC, 0xDC]), bytes([SLIP_END])).replace(
                bytes([SLIP_ESC, 0xDD]), bytes([SLIP_ESC]))
            self.buf.clear()
            if len(raw) >= 5 and crc16(raw[:-2]) == struct.unpack("<H", raw[-2:])[0]:
                self.frames.append(raw)


def kinds(frames):
    return [f[0] for f in frames]


async def firmware_over_rfcomm(device, name, done):
    conn = await device.connect(ROBOT_ADDRESS, transport=core.PhysicalTransport.BR_EDR)
    await conn.authenticate()
    channel = await rfcomm.find_rfcomm_channel_with_uuid(conn, SPP_UUID)
    mux = await rfcomm.Client(conn).start()
    dlc = await mux.open_dlc(channel)
    rx = SlipFrames()
    dlc.sink = rx.feed
    dlc.write(slip(frame(PKT_HELLO_REQUEST, 0, struct.pack("<HI", protocol_version(), 0x5EED0001))))
    await wait_for(lambda: PKT_HELLO in kinds(rx.frames), 5, f"{name}: no hello over RFCOMM")
    hello = next(f for f in rx.frames if f[0] == PKT_HELLO)
    assert hello[3] == 7, f"{name}: hello from robot {hello[3]}"
    await wait_for(lambda: kinds(rx.frames).count(PKT_STATE_FULL) >= 3, 5, f"{name}: no state over RFCOMM")
    await done.wait()  # the other peer has its state too
    await dlc.disconnect()
    await mux.disconnect()
    await conn.disconnect()
    return True


async def firmware_over_l2cap(device, name, done):
    conn = await device.connect(ROBOT_ADDRESS, transport=core.PhysicalTransport.BR_EDR)
    await conn.authenticate()
    l2 = await conn.create_l2cap_channel(spec=l2cap.ClassicChannelSpec(psm=PSM_FRAMED, mtu=200))
    sdus = []
    l2.sink = sdus.append
    l2.write(frame(PKT_HELLO_REQUEST, 0, struct.pack("<HI", protocol_version(), 0x5EED0002)))
    await wait_for(lambda: PKT_HELLO in kinds(sdus), 5, f"{name}: no hello over the framed channel")
    await wait_for(lambda: kinds(sdus).count(PKT_STATE_FULL) >= 3, 5, f"{name}: no state over the framed channel")
    assert all(crc16(s[:-2]) == struct.unpack("<H", s[-2:])[0] for s in sdus), f"{name}: a frame with a bad CRC"
    done.set()
    seen = len(sdus)
    await asyncio.sleep(1.0)  # the other peer leaves meanwhile: this one keeps its state
    assert kinds(sdus[seen:]).count(PKT_STATE_FULL) >= 3, f"{name}: state stopped when the other peer left"
    await l2.disconnect()
    await conn.disconnect()
    return True


async def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("robot")
    parser.add_argument("--firmware", action="store_true", help="ROBOT is tests/bt_robot.c: talk PocketBot to it")
    parser.add_argument("--trace")
    parser.add_argument("--trace-c", help="write the recorded session as tests/bt_trace.h")
    parser.add_argument("--peers", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=20)
    args = parser.parse_args()

    link = LocalLink()
    robot_ctrl = RobotController("robot", link=link, public_address=ROBOT_ADDRESS)
    trace = [] if (args.trace or args.trace_c) else None
    wire = RobotWire(robot_ctrl, trace)
    loop = asyncio.get_running_loop()
    server = await loop.create_server(lambda: wire, "127.0.0.1", 0)
    port = server.sockets[0].getsockname()[1]
    command = [args.robot, str(port), "30"] if args.firmware else [args.robot, "--live", str(port), "30"]
    robot = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)

    devices = []
    for i in range(args.peers):
        ctrl = Controller(f"peer{i}", link=link, public_address=f"B0:00:00:00:00:{i + 1:02X}")
        device = Device.with_hci(f"peer{i}", hci.Address(f"B0:00:00:00:00:{i + 1:02X}"), ctrl, ctrl)
        device.classic_enabled = True
        await device.power_on()
        devices.append(device)

    ok = False
    try:
        await wait_for(lambda: robot_ctrl.classic_scan_enable == 3, 10, "the robot's controller made connectable")
        if args.firmware:
            done = asyncio.Event()
            results = await asyncio.gather(firmware_over_rfcomm(devices[0], "peer0", done),
                                           firmware_over_l2cap(devices[1], "peer1", done))
        else:
            results = await asyncio.gather(*(peer_session(d, f"peer{i}", args.rounds) for i, d in enumerate(devices)))
        ok = all(results)
    except Exception as e:
        print(f"FAIL: {e!r}")
    finally:
        robot.terminate()
        out, _ = robot.communicate(timeout=10)
        print(out.strip())
        server.close()
    if args.trace:
        with open(args.trace, "w") as f:
            for t, d, data in trace:
                f.write(f"{t:.4f} {d} {data.hex()}\n")
    if args.trace_c and ok:
        write_trace_c(args.trace_c, trace)
    print("bt_e2e: " + ("every check held" if ok else "FAILED"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(asyncio.run(main()))

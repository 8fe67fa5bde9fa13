"""
Virtual Bluetooth for PocketBot (see README.md beside this file): N Bumble BR/EDR controllers on one virtual link,
each an H4 byte stream on a TCP port for a robot's firmware to drive, and a computer-side gateway (a Bumble host on
a controller of its own on the same link) that pages a robot by address, finds its services by SDP and offers them
as local TCP endpoints:

  rfcomm  the robot's Serial Port Profile channel as a byte stream (SLIP frames, as on any PocketBot stream link);
  l2cap   the robot's framed L2CAP channel, one PocketBot frame per SDU, each carried on TCP as a 2-byte
          little-endian length followed by the frame.

A TCP client connecting to an endpoint opens the Bluetooth side (page, SDP, channel); when either side closes, the
other is closed too, and the ACL link is released once no channel uses it. A new client takes the endpoint over.

Standard output, one line each (ports are ephemeral and printed for the caller):
  controller <index> <bdaddr> h4 <host>:<port>
  gateway <bdaddr>
  ready
Standard input, one command a line, each answered by one line `ok ...` or `error <why>`:
  bridge <bdaddr>   -> ok bridge <bdaddr> rfcomm <host>:<port> l2cap <host>:<port>
  drop <bdaddr> [s] the radio link between gateway and robot is lost (supervision timeout on both sides), and the
                    robot stays out of the gateway's reach for s seconds (default 0: pages find it again at once)
  reset <index>     controller <index> power-cycles: its links are lost, it forgets everything, says nothing
  quit              (or end of input) stops everything
"""

import argparse
import asyncio
import logging
import socket
import struct
import sys

from bumble import core, hci, l2cap, lmp, rfcomm, sdp
from bumble.controller import Controller
from bumble.device import Device, DeviceConfiguration
from bumble.host import Host
from bumble.keys import MemoryKeyStore
from bumble.link import LocalLink
from bumble.transport.common import AsyncPipeSink, PacketParser

# What the firmware serves (firmware/bluetooth/bt_config.h): SPP on an RFCOMM channel, and PocketBot frames on an L2CAP PSM
# announced by an SDP record with this service class.
SPP_UUID = core.UUID.from_16_bits(0x1101)
FRAMED_SERVICE_UUID = core.UUID('6e2a6f10-5b1e-4c3a-9a4e-70b0c4e7b001')
# Robots' controllers are 00:B0:7B:00:00:<index>, the gateway's 00:B0:7B:00:00:00.
ADDRESS_PREFIX = '00:B0:7B:00:00:'
PAGE_TIMEOUT_S = 5.12  # the HCI default (0x2000 slots)
CONNECTION_ACCEPT_TIMEOUT_S = 5.0  # the HCI default (0x1F40 slots)
SUPERVISION_TIMEOUT = hci.HCI_ErrorCode.CONNECTION_TIMEOUT_ERROR
# The gateway's L2CAP MTU for the framed channel: any PocketBot frame (at most 125 bytes) fits.
FRAMED_MTU = 512
LENGTH_PREFIX = struct.Struct('<H')

log = logging.getLogger('virtual_bluetooth')


class VirtualController(Controller):
    """A Bumble controller that behaves as a real one where PocketBot's stack depends on it: a page reaches it only
    while its host has page scan on, a connection request its host leaves unanswered is refused after the
    Connection Accept Timeout (Bumble's would wait forever), HCI_Reset drops its links and scans (Bumble's keeps
    them), Read_Scan_Enable is answered (Bumble's leaves it unanswered; the robot's keep-alive reads it), and its ACL
    buffers are those of a typical BR/EDR module instead of Bumble's LE-sized 27 bytes.

    A link it drops is reported to the peer at once, as if its supervision timeout (20 s by default) had passed."""

    def __init__(self, name, link, address, acl_length, acl_packets):
        super().__init__(name, link=link, public_address=address)
        self.acl_data_packet_length = acl_length
        self.total_num_acl_data_packets = acl_packets

    def on_lmp_packet(self, sender_address, packet):
        if isinstance(packet, lmp.LmpHostConnectionReq):
            if not self.classic_scan_enable & 0x02:
                self.refuse(sender_address, hci.HCI_ErrorCode.PAGE_TIMEOUT_ERROR)
                return
            asyncio.get_running_loop().call_later(CONNECTION_ACCEPT_TIMEOUT_S, self.accept_timeout, sender_address)
        super().on_lmp_packet(sender_address, packet)

    def on_hci_read_scan_enable_command(self, command):
        # Bumble knows no Read_Scan_Enable class: the command arrives generic, and its Command Complete is sent here.
        scans = bytes([hci.HCI_SUCCESS, self.classic_scan_enable])
        self.send_hci_packet(hci.HCI_Command_Complete_Event(
            num_hci_command_packets=1, command_opcode=command.op_code,
            return_parameters=hci.HCI_GenericReturnParameters(data=scans)))

    def on_hci_reset_command(self, command):
        self.drop_links()
        self.classic_scan_enable = 0
        return super().on_hci_reset_command(command)

    def drop_links(self):
        """Forgets every BR/EDR link without a word to its own host; each peer's controller reports it lost."""
        for peer in list(self.classic_connections):
            other = self.link.find_classic_controller(peer)
            if other is not None:
                other.on_classic_disconnected(self.public_address, SUPERVISION_TIMEOUT)
        self.classic_connections.clear()

    def refuse(self, pager, reason):
        self.send_lmp_packet(pager, lmp.LmpNotAccepted(lmp.Opcode.LMP_HOST_CONNECTION_REQ, reason))

    def accept_timeout(self, pager):
        connection = self.classic_connections.get(pager)
        if connection is None or connection.handle != 0:  # accepted (it has a handle), refused or gone meanwhile
            return
        del self.classic_connections[pager]
        self.refuse(pager, hci.HCI_ErrorCode.CONNECTION_ACCEPT_TIMEOUT_ERROR)
        self.send_hci_packet(hci.HCI_Connection_Complete_Event(
            status=hci.HCI_ErrorCode.CONNECTION_ACCEPT_TIMEOUT_ERROR, connection_handle=0, bd_addr=pager,
            link_type=hci.HCI_Connection_Complete_Event.LinkType.ACL, encryption_enabled=0))


class H4Port:
    """One robot's controller behind an H4 TCP server. The newest client is the robot's UART: an older connection's
    late end does not cut it off (Bumble's own TCP server transport shares one sink between its connections).
    reset() swaps in a fresh controller on the same port."""

    def __init__(self, index, link, args):
        self.index = index
        self.link = link
        self.args = args
        self.address = hci.Address(f'{ADDRESS_PREFIX}{index:02X}', hci.Address.PUBLIC_DEVICE_ADDRESS)
        self.writer = None
        self.controller = None
        self._new_controller()

    async def start(self, sock):
        self.server = await asyncio.start_server(self.serve, sock=sock)

    async def serve(self, reader, writer):
        if self.writer is not None:
            self.writer.close()
        self.writer = writer
        parser = PacketParser(FromRobot(self))
        try:
            while data := await reader.read(4096):
                try:
                    parser.feed_data(data)
                except core.InvalidPacketError as e:  # a bad packet type: the parser starts over, as a controller's
                    log.info('controller %d: %s', self.index, e)
        except ConnectionError:
            pass
        finally:
            if self.writer is writer:
                self.writer = None
            writer.close()

    def _new_controller(self):
        self.controller = VirtualController(f'robot-{self.index}', self.link, self.address,
                                            self.args.acl_length, self.args.acl_packets)
        self.controller.host = self

    def on_packet(self, packet):  # the controller's, to the robot
        if self.writer is not None:
            self.writer.write(packet)

    def reset(self):
        old = self.controller
        old.drop_links()
        old.host = None
        self.link.remove_controller(old)
        self._new_controller()


class FromRobot:
    """Where the H4 parser puts the robot's packets: the port's controller of the moment."""

    def __init__(self, port):
        self.port = port

    def on_packet(self, packet):
        self.port.controller.on_packet(packet)


class Pipe:
    """A TCP client joined to one Bluetooth channel; close() ends both, once."""

    def __init__(self, writer, closer):
        self.writer = writer
        self.closer = closer
        self.closed = asyncio.get_running_loop().create_future()

    def close(self):
        if self.closed.done():
            return
        self.closed.set_result(None)
        self.writer.close()
        # Kept: asyncio holds only a weak reference to a task, which could vanish before closing the channel.
        self.closing = asyncio.get_running_loop().create_task(self.closer())


class Bridge:
    """The gateway's two TCP endpoints for one robot, and the ACL connection they share."""

    def __init__(self, gateway, address):
        self.gateway = gateway
        self.device = gateway.device
        self.address = hci.Address(address, hci.Address.PUBLIC_DEVICE_ADDRESS)
        self.connection = None
        self.mux = None
        self.connecting = asyncio.Lock()
        self.pipes = {}  # 'rfcomm' / 'l2cap' -> Pipe
        self.out_of_reach_until = 0.0  # loop time before which pages fail, as for a robot out of range

    async def start(self, host):
        self.rfcomm_server = await asyncio.start_server(lambda r, w: self.serve('rfcomm', r, w), host, 0)
        self.l2cap_server = await asyncio.start_server(lambda r, w: self.serve('l2cap', r, w), host, 0)

    def ports(self):
        return self.rfcomm_server.sockets[0].getsockname()[1], self.l2cap_server.sockets[0].getsockname()[1]

    async def acl(self):
        async with self.connecting:
            if self.connection is None:
                if asyncio.get_running_loop().time() < self.out_of_reach_until:
                    raise core.ConnectionError(hci.HCI_ErrorCode.PAGE_TIMEOUT_ERROR, core.PhysicalTransport.BR_EDR,
                                               self.address, 'hci', 'page timeout: the robot is out of reach')
                # Bounded here too: Bumble's own timeout waits for a Create_Connection_Cancel its controller lacks.
                connection = await asyncio.wait_for(self.device.connect(
                    self.address, transport=core.PhysicalTransport.BR_EDR, timeout=PAGE_TIMEOUT_S),
                    PAGE_TIMEOUT_S + CONNECTION_ACCEPT_TIMEOUT_S)
                connection.on('disconnection', lambda reason: self.on_disconnection(connection, reason))
                self.connection = connection
                self.mux = None
            return self.connection

    def on_disconnection(self, connection, reason):
        log.info('%s: ACL link lost (%s)', self.address, hci.HCI_Constant.error_name(reason))
        if self.connection is connection:
            self.connection = None
            self.mux = None
        for pipe in list(self.pipes.values()):
            pipe.close()

    async def release_if_idle(self):
        if not self.pipes and self.connection is not None:
            connection, self.connection, self.mux = self.connection, None, None
            try:
                await connection.disconnect()
            except Exception as e:  # already gone
                log.info('%s: disconnect: %s', self.address, e)

    async def serve(self, kind, reader, writer):
        old = self.pipes.pop(kind, None)
        if old is not None:
            old.close()
            await old.closed
        try:
            channel = await (self.open_rfcomm() if kind == 'rfcomm' else self.open_l2cap())
        except Exception as e:
            log.warning('%s: cannot open %s: %s', self.address, kind, describe(e))
            writer.close()
            await self.release_if_idle()
            return
        pipe = Pipe(writer, lambda: self.close_channel(kind, channel))
        self.pipes[kind] = pipe
        channel.on('close', pipe.close)
        try:
            if kind == 'rfcomm':
                channel.sink = writer.write
                await self.stream_to_rfcomm(reader, channel, pipe)
            else:
                channel.sink = lambda sdu: writer.write(LENGTH_PREFIX.pack(len(sdu)) + sdu)
                await self.frames_to_l2cap(reader, channel, pipe)
        except (ConnectionError, asyncio.IncompleteReadError, core.BaseBumbleError) as e:
            log.info('%s: %s pipe ended: %r', self.address, kind, e)
        finally:
            pipe.close()

    async def open_rfcomm(self):
        connection = await self.acl()
        channel = await rfcomm.find_rfcomm_channel_with_uuid(connection, SPP_UUID)
        if channel is None:
            raise core.InvalidStateError('no Serial Port Profile record')
        if self.mux is None:
            self.mux = await rfcomm.Client(connection).start()
        return await self.mux.open_dlc(channel)

    async def open_l2cap(self):
        connection = await self.acl()
        psm = await find_framed_psm(connection)
        return await connection.create_l2cap_channel(spec=l2cap.ClassicChannelSpec(psm=psm, mtu=FRAMED_MTU))

    async def stream_to_rfcomm(self, reader, dlc, pipe):
        while not pipe.closed.done():
            data = await reader.read(4096)
            if not data:
                return
            dlc.write(data)
            await dlc.drain()

    async def frames_to_l2cap(self, reader, channel, pipe):
        while not pipe.closed.done():
            (length,) = LENGTH_PREFIX.unpack(await reader.readexactly(LENGTH_PREFIX.size))
            frame = await reader.readexactly(length)
            if length > channel.peer_mtu:
                log.warning('%s: a %d-byte frame exceeds the robot\'s MTU %d: dropped', self.address, length,
                            channel.peer_mtu)
                continue
            channel.write(frame)

    async def close_channel(self, kind, channel):
        if self.pipes.get(kind) is not None and self.pipes[kind].closed.done():
            del self.pipes[kind]
        try:
            if kind == 'rfcomm' and channel.state == rfcomm.DLC.State.CONNECTED:
                await channel.disconnect()
            elif kind == 'l2cap' and channel.state == l2cap.ClassicChannel.State.OPEN:
                await channel.disconnect()
        except Exception as e:
            log.info('%s: closing %s: %r', self.address, kind, e)
        await self.release_if_idle()


def describe(error):
    """Bumble's errors often print as `ConnectionError()`: their name and code say more."""
    name = getattr(error, 'error_name', '') or str(error)
    return f'{type(error).__name__} {name}'.strip()


async def find_framed_psm(connection):
    """The PSM of the robot's framed PocketBot service, from its SDP record."""
    async with sdp.Client(connection) as client:
        records = await client.search_attributes(
            uuids=[FRAMED_SERVICE_UUID], attribute_ids=[sdp.SDP_PROTOCOL_DESCRIPTOR_LIST_ATTRIBUTE_ID])
    for attributes in records:
        for attribute in attributes:
            if attribute.id == sdp.SDP_PROTOCOL_DESCRIPTOR_LIST_ATTRIBUTE_ID:
                # [[L2CAP, PSM]]
                l2cap_descriptor = attribute.value.value[0].value
                if len(l2cap_descriptor) >= 2:
                    return l2cap_descriptor[1].value
    raise core.InvalidStateError('no framed PocketBot service record')


class Gateway:
    def __init__(self, link, host):
        self.host = host
        self.address = hci.Address(f'{ADDRESS_PREFIX}00', hci.Address.PUBLIC_DEVICE_ADDRESS)
        self.controller = VirtualController('gateway', link, self.address, 1021, 8)
        config = DeviceConfiguration(name='PocketBot gateway', address=self.address, classic_enabled=True,
                                     le_enabled=False, connectable=False, discoverable=False)
        self.device = Device(config=config, host=Host(self.controller, AsyncPipeSink(self.controller)))
        self.device.keystore = MemoryKeyStore()
        self.bridges = {}

    async def start(self):
        await self.device.power_on()

    async def bridge(self, address):
        key = address.upper()
        if key not in self.bridges:
            b = Bridge(self, key)
            await b.start(self.host)
            self.bridges[key] = b
        return self.bridges[key]

    async def drop(self, address, seconds):
        robot = self.controller.link.find_classic_controller(hci.Address(address, hci.Address.PUBLIC_DEVICE_ADDRESS))
        if robot is None or self.address not in robot.classic_connections:
            raise core.InvalidStateError(f'no link to {address}')
        (await self.bridge(address)).out_of_reach_until = asyncio.get_running_loop().time() + seconds
        robot.on_classic_disconnected(self.address, SUPERVISION_TIMEOUT)
        self.controller.on_classic_disconnected(robot.public_address, SUPERVISION_TIMEOUT)


async def commands(gateway, ports):
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader()
    await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin)
    while True:
        line = (await reader.readline()).decode().split()
        if not line:
            if reader.at_eof():
                return
            continue
        verb, args = line[0], line[1:]
        try:
            if verb == 'quit':
                return
            elif verb == 'bridge' and len(args) == 1:
                b = await gateway.bridge(args[0])
                rf, l2 = b.ports()
                say(f'ok bridge {b.address.to_string(False)} rfcomm {gateway.host}:{rf} l2cap {gateway.host}:{l2}')
            elif verb == 'drop' and len(args) in (1, 2):
                await gateway.drop(args[0], float(args[1]) if len(args) == 2 else 0.0)
                say('ok drop')
            elif verb == 'reset' and len(args) == 1:
                ports[int(args[0]) - 1].reset()
                say('ok reset')
            else:
                say(f'error unknown command: {" ".join(line)}')
        except Exception as e:
            say(f'error {e}')


def say(text):
    print(text, flush=True)


async def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--controllers', type=int, default=1, help='robots\' controllers (1..254)')
    parser.add_argument('--host', default='127.0.0.1', help='address every TCP port listens on')
    parser.add_argument('--acl-length', type=int, default=310,
                        help='ACL data packet length the robots\' controllers announce (Read_Buffer_Size)')
    parser.add_argument('--acl-packets', type=int, default=10, help='ACL buffers the robots\' controllers announce')
    parser.add_argument('-v', '--verbose', action='count', default=0, help='log to stderr (-vv: every HCI packet)')
    args = parser.parse_args()
    if not 1 <= args.controllers <= 254:
        parser.error('--controllers must be 1..254')
    logging.basicConfig(stream=sys.stderr, format='%(asctime)s %(name)s %(levelname)s %(message)s',
                        level=[logging.WARNING, logging.INFO, logging.DEBUG][min(args.verbose, 2)])

    link = LocalLink()
    ports = []
    for i in range(1, args.controllers + 1):
        port = H4Port(i, link, args)
        sock = socket.create_server((args.host, 0))
        await port.start(sock)
        ports.append(port)
        say(f'controller {i} {port.address.to_string(False)} h4 {args.host}:{sock.getsockname()[1]}')
    gateway = Gateway(link, args.host)
    await gateway.start()
    say(f'gateway {gateway.address.to_string(False)}')
    say('ready')
    await commands(gateway, ports)


if __name__ == '__main__':
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        pass

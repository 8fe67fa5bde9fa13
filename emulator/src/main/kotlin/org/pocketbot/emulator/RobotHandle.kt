package org.pocketbot.emulator

import org.pocketbot.emulator.bluetooth.H4Uart
import org.pocketbot.emulator.link.LinkSettings
import org.pocketbot.emulator.transport.InProcessDevice
import org.pocketbot.emulator.transport.InProcessTransport
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.emulator.transport.TcpEndpoint
import org.pocketbot.sdk.Pose
import org.pocketbot.protocol.Crc16
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.RobotState
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.StateFull
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport
import java.net.InetAddress
import java.net.InetSocketAddress

/** Total travel of each wheel on the ground, in metres (signed: backwards is negative). */
public class WheelDistances(public val leftM: Double, public val rightM: Double) {
    override fun equals(other: Any?): Boolean = other is WheelDistances && other.leftM == leftM && other.rightM == rightM
    override fun hashCode(): Int = 31 * leftM.hashCode() + rightM.hashCode()
    override fun toString(): String = "WheelDistances(left $leftM m, right $rightM m)"
}

/**
 * One robot of an [Emulator]: its ground truth, its firmware's own state read straight from WebAssembly memory,
 * its connections, and fault injection. Safe to call from any thread; reads are consistent with a step boundary.
 */
public class RobotHandle internal constructor(
    internal val emulator: Emulator,
    internal val sim: SimRobot,
    private val lock: Any,
) {
    public val id: Int get() = sim.id

    /** The name the firmware advertises (settings.identity.name), e.g. `PocketBot-3`. */
    public val name: String get() = synchronized(lock) {
        val bytes = sim.firmware.readBytes(sim.firmware.settingsAddress + NAME_FIELD.offset, NAME_FIELD.size)
        val end = bytes.indexOf(0).let { if (it < 0) bytes.size else it }
        String(bytes, 0, end, Charsets.US_ASCII)
    }

    /**
     * Power-cycles this robot: its firmware starts afresh (a new instance, all RAM lost) at the current simulated
     * time and sends `hello` as a real robot does at reset; the EEPROM (settings saved with `save_settings`) is
     * kept. The body and its pose stay as they are; the host on the robot's first link (its UART) stays connected and
     * gets the hello, hosts on its other links lose them (as a Bluetooth robot's links drop when it resets).
     */
    public fun reset(): Unit = synchronized(lock) { sim.reset(emulator.timeTicks) }

    /**
     * True pose of the axle midpoint (ground truth, the same frame as the world file's), its heading in -pi..pi as
     * the SDK's odometry has it.
     */
    public val truePose: Pose get() = synchronized(lock) { Pose(sim.x, sim.y, sim.theta) }

    /** True travel of both wheels since the robot was added. */
    public val trueWheelDistances: WheelDistances get() = synchronized(lock) { WheelDistances(sim.distL, sim.distR) }

    /** Motor duty the firmware drives now, permille. */
    public val pwmPermille: Pair<Int, Int> get() = synchronized(lock) { Pair((sim.dutyL * 1000).toInt(), (sim.dutyR * 1000).toInt()) }

    /** The status LED bit mask the firmware drives. */
    public val led: Int get() = synchronized(lock) { sim.led }

    /** The firmware's robot_state bytes, straight from its linear memory. */
    public fun stateBytes(): ByteArray = synchronized(lock) { sim.firmware.readBytes(sim.firmware.stateAddress, ProtocolInfo.STATE_SIZE) }

    /** The firmware's settings bytes. */
    public fun settingsBytes(): ByteArray = synchronized(lock) { sim.firmware.readBytes(sim.firmware.settingsAddress, ProtocolInfo.SETTINGS_SIZE) }

    /** The firmware's robot_state, decoded with the SDK's codec. */
    public fun state(): RobotState {
        val payload = stateBytes()
        // Decoded through the public frame codec: a state_full frame around the raw struct.
        val frame = ByteArray(Frames.HEADER_SIZE + payload.size + Frames.CRC_SIZE)
        frame[0] = StateFull.TYPE.toByte(); frame[1] = 0; frame[2] = payload.size.toByte()
        payload.copyInto(frame, Frames.HEADER_SIZE)
        val crc = Crc16.compute(frame, 0, Frames.HEADER_SIZE + payload.size)
        frame[frame.size - 2] = crc.toByte(); frame[frame.size - 1] = (crc shr 8).toByte()
        return when (val r = Frames.decode(frame)) {
            is FrameResult.Decoded -> (r.packet as StateFull).state
            is FrameResult.Failed -> error("robot_state in memory does not decode: ${r.error}")
        }
    }

    /** Puts the robot somewhere else (a hand lifting and placing it); the wheels stop. */
    public fun place(pose: Pose): Unit = synchronized(lock) { sim.place(pose) }

    // ---- link and faults ----------------------------------------------------------------------------------------

    /** The link model of every host link now; assign to change it while running (fault injection). */
    public var link: LinkSettings
        get() = sim.links.settings
        set(value) { sim.links.applySettings(value) }

    /** Sensor noise and wheel slip of this robot; assign to change them while running. */
    public var noise: NoiseSettings
        get() = sim.noise
        set(value) = synchronized(lock) { sim.noise = value }

    /** Takes the links down: host connections are lost and nothing passes until [reconnectLink]. */
    public fun disconnectLink() { link = link.withConnected(false) }

    public fun reconnectLink() { link = link.withConnected(true) }

    /** Bytes the links delivered to hosts, lost, and corrupted so far. */
    public val linkBytesToHost: Long get() = sim.links.bytesToHost
    public val linkBytesLost: Long get() = sim.links.bytesLost
    public val linkBytesCorrupted: Long get() = sim.links.bytesCorrupted

    /** Host bytes the links dropped because their buffer ([LinkSettings.bufferBytes]) was full: a host that sends
     *  faster than the baud rate carries. */
    public val linkBytesOverflowed: Long get() = sim.links.bytesOverflowed

    /** How many hosts the robot can serve at once: its firmware's host links. */
    public val hostLinks: Int get() = sim.links.all.size

    /** How many hosts are connected to it now (in process and over TCP). */
    public val hostsConnected: Int get() = sim.links.attached

    // ---- connections --------------------------------------------------------------------------------------------

    public val address: String get() = "emulator:$id"

    /** Puts raw bytes (SLIP frames) on the robot's first link (its UART) as if a host had sent them, without a
     *  connection; the firmware is told a host came when none is on that link. */
    public fun hostSendRaw(bytes: ByteArray) { sim.link.rawSend(bytes) }

    /** Opens an in-process transport (SLIP through a simulated link of its own); throws
     *  [org.pocketbot.sdk.transport.TransportLostException] when every host link of the robot is in use. */
    public fun openTransport(): Transport = InProcessTransport(sim.links, address)

    /** This robot as a discoverable device. */
    public fun device(): RobotDevice = InProcessDevice(name, address, sim.links, emulator)

    private var tcp: TcpEndpoint? = null

    /** The TCP port of this robot's endpoint, or -1 when it has none. */
    public val tcpPort: Int get() = tcp?.port ?: -1

    /** The first of [tcpClients], or null. */
    public val tcpClient: InetSocketAddress? get() = tcpClients.firstOrNull()

    /** The hosts connected to this robot's TCP endpoint now (address and port), in the order they came. */
    public val tcpClients: List<InetSocketAddress> get() = tcp?.clients ?: emptyList()

    /**
     * Opens a TCP endpoint for this robot on [listen]:[port] (0: any free port); returns the port. By default only
     * programs on this machine reach it; [ListenAddress.ANY] puts it on the network. Throws [java.net.BindException]
     * when the port is taken or [listen] is no address of this machine.
     */
    public fun startTcp(port: Int = 0, listen: InetAddress = ListenAddress.LOOPBACK): Int = synchronized(this) {
        tcp?.let { return it.port }
        TcpEndpoint(sim.links, listen, port, "robot-$id").also { tcp = it }.port
    }

    internal fun closeTcp() { synchronized(this) { tcp?.close(); tcp = null } }

    private var h4: H4Uart? = null

    /**
     * Wires this robot's UART to the Bluetooth controller at [controller], an H4 byte stream on TCP (a
     * [org.pocketbot.emulator.bluetooth.VirtualBluetooth] controller, or Bumble's HCI bridge in front of a real
     * dongle): for a robot running the HCI firmware ([org.pocketbot.emulator.firmware.FirmwareImage.compiledHci]).
     * The UART then belongs to the controller: hosts reach the robot over Bluetooth, not over [startTcp] or
     * [openTransport]. The link model ([link]) is the wire between the two: its faults are faults on the H4 wire.
     */
    public fun attachH4(controller: InetSocketAddress): Unit = synchronized(this) {
        check(h4 == null) { "robot $id is wired to a controller already" }
        h4 = H4Uart(sim.link, controller, "robot-$id")
    }

    /** Unwires the UART from its controller (see [attachH4]). */
    public fun detachH4(): Unit = synchronized(this) { h4?.close(); h4 = null }

    override fun toString(): String = "robot $id"

    private companion object {
        val NAME_FIELD = SETTINGS_FIELDS.single { it.path == "identity.name" }
    }
}

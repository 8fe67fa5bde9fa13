package org.pocketbot.sdk.transport

/**
 * A robot on a serial port (see [SerialTransport]): an RFCOMM tty bound to the robot's Bluetooth address, a USB
 * serial adapter, a pty. Creating it does not open the port; [open] does, each time it is called.
 *
 * ```
 * val transport = SerialRobotDevice("/dev/rfcomm0").open()
 * ```
 *
 * @param path the port, e.g. `/dev/rfcomm0`, `/dev/ttyUSB0`, `COM3`.
 * @param baud the line speed in bit/s (an RFCOMM tty ignores it).
 * @param name the robot's name, as a person would call it; the path unless given.
 */
public class SerialRobotDevice(
    public val path: String,
    public val baud: Int = SerialTransport.DEFAULT_BAUD,
    override val name: String = path,
) : RobotDevice {
    override val address: String = SerialTransport.serialAddress(path)

    /** [baud] with 8N1 framing (an RFCOMM tty carries what the robot's Bluetooth module bridges: 115200 Bd). */
    override val linkRate: LinkRate get() = LinkRate.ofBaud(baud)

    /** Opens the port; throws [TransportLostException] when it cannot. Safe from any coroutine. */
    override suspend fun open(): Transport = SerialTransport.open(path, baud)

    override fun toString(): String = "$name ($address)"
    override fun equals(other: Any?): Boolean =
        other is SerialRobotDevice && other.path == path && other.baud == baud && other.name == name
    override fun hashCode(): Int = (path.hashCode() * 31 + baud) * 31 + name.hashCode()
}

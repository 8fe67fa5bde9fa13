package org.pocketbot.sdk.transport

import kotlinx.coroutines.CoroutineDispatcher
import org.pocketbot.sdk.transport.internal.SocketLoop
import kotlin.time.Duration

/**
 * A robot reachable over TCP at [host]:[port]: an emulated robot, a real one behind a serial-to-TCP bridge, or one
 * reached over Bluetooth through the gateway of emulator/bluetooth (its RFCOMM endpoint carries SLIP, its L2CAP
 * endpoint frames with a length before each). Creating it does not connect; [open] does, each time it is called.
 *
 * ```
 * val transport = TcpRobotDevice("127.0.0.1", 40001).open()
 * ```
 *
 * @param name the robot's name, as a person would call it; the address unless given.
 * @param connectTimeout how long [open] waits for the connection.
 * @param framing how frames travel on the connection: SLIP ([TcpTransport]) unless told otherwise.
 */
public class TcpRobotDevice(
    public val host: String,
    public val port: Int,
    override val name: String = TcpTransport.tcpAddress(host, port),
    public val connectTimeout: Duration = TcpTransport.DEFAULT_CONNECT_TIMEOUT,
    public val framing: TcpFraming = TcpFraming.SLIP,
) : RobotDevice {
    init {
        require(port in 1..65535) { "port $port is not a TCP port" }
    }

    override val address: String = TcpTransport.tcpAddress(host, port)

    private val loop = SocketLoop.next()

    /** The event loop that serves this robot's socket (one of a few, taken in turn): its link runs there too. */
    override val eventLoop: CoroutineDispatcher get() = loop

    /** Connects; throws [TransportLostException] when nothing answers at [address]. Safe from any coroutine. */
    override suspend fun open(): Transport = when (framing) {
        TcpFraming.SLIP -> TcpTransport.connect(host, port, connectTimeout, loop = loop)
        TcpFraming.LENGTH_PREFIXED -> FramedTcpTransport.connect(host, port, connectTimeout, loop = loop)
    }

    override fun toString(): String = "$name ($address)"
    override fun equals(other: Any?): Boolean =
        other is TcpRobotDevice && other.host == host && other.port == port && other.name == name && other.framing == framing
    override fun hashCode(): Int = ((host.hashCode() * 31 + port) * 31 + name.hashCode()) * 31 + framing.hashCode()
}

/** How frames travel on a TCP connection to a robot. */
public enum class TcpFraming {
    /** SLIP, as on every PocketBot stream link ([TcpTransport]). */
    SLIP,

    /** Each frame whole after a 2-byte little-endian length ([FramedTcpTransport]): a Bluetooth L2CAP channel's frames. */
    LENGTH_PREFIXED,
}

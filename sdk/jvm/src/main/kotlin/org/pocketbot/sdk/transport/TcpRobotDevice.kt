package org.pocketbot.sdk.transport

import kotlinx.coroutines.CoroutineDispatcher
import org.pocketbot.sdk.transport.internal.SocketLoop
import kotlin.time.Duration

/**
 * A robot reachable over TCP at [host]:[port] (see [TcpTransport]): an emulated robot, or a real one behind a
 * serial-to-TCP bridge. Creating it does not connect; [open] does, each time it is called.
 *
 * ```
 * val transport = TcpRobotDevice("127.0.0.1", 40001).open()
 * ```
 *
 * @param name the robot's name, as a person would call it; the address unless given.
 * @param connectTimeout how long [open] waits for the connection.
 */
public class TcpRobotDevice(
    public val host: String,
    public val port: Int,
    override val name: String = TcpTransport.tcpAddress(host, port),
    public val connectTimeout: Duration = TcpTransport.DEFAULT_CONNECT_TIMEOUT,
) : RobotDevice {
    init {
        require(port in 1..65535) { "port $port is not a TCP port" }
    }

    override val address: String = TcpTransport.tcpAddress(host, port)

    private val loop = SocketLoop.next()

    /** The event loop that serves this robot's socket (one of a few, taken in turn): its link runs there too. */
    override val eventLoop: CoroutineDispatcher get() = loop

    /** Connects; throws [TransportLostException] when nothing answers at [address]. Safe from any coroutine. */
    override suspend fun open(): Transport = TcpTransport.connect(host, port, connectTimeout, loop = loop)

    override fun toString(): String = "$name ($address)"
    override fun equals(other: Any?): Boolean =
        other is TcpRobotDevice && other.host == host && other.port == port && other.name == name
    override fun hashCode(): Int = (host.hashCode() * 31 + port) * 31 + name.hashCode()
}

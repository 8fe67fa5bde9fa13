package org.pocketbot.emulator.transport

import org.pocketbot.emulator.RobotHandle
import java.net.InetAddress

/**
 * The control port of a running emulator, on [listen] (the robots' endpoints listen there too): a client that
 * connects gets one line per robot, `<id>\t<name>\t<tcp port>\t<host>\n` (ASCII, robots in the order they were
 * added; the port is the robot's TCP endpoint, [portOf] of it), then the connection closes. `host` is the address of this machine the client reached, so it names a host
 * the client can reach the robots at even when [listen] is the wildcard address. See emulator/README.md.
 */
internal class ControlPort(
    listen: InetAddress,
    port: Int,
    private val robots: () -> List<RobotHandle>,
    private val portOf: (RobotHandle) -> Int,
) : AutoCloseable {
    private val acceptor = Acceptor(listen, port, backlog = 16, name = "emulator-control") { s ->
        s.use {
            val host = it.localAddress.hostAddress.substringBefore('%')
            val text = buildString { for (r in robots()) append(line(r.id, r.name, portOf(r), host)) }
            it.getOutputStream().write(text.toByteArray(Charsets.US_ASCII))
            it.getOutputStream().flush()
        }
    }
    val port: Int = acceptor.port

    override fun close() = acceptor.close()

    companion object {
        fun line(id: Int, name: String, port: Int, host: String): String = "$id\t$name\t$port\t$host\n"
    }
}

package org.pocketbot.emulator.transport

import org.pocketbot.emulator.RobotHandle
import java.io.IOException
import java.net.InetAddress
import java.net.InetSocketAddress
import java.net.ServerSocket

/**
 * The control port of a running emulator, on 127.0.0.1: a client that connects gets one line per robot,
 * `<id>\t<name>\t<tcp port>\n` (ASCII, robots in the order they were added), then the connection closes.
 * See emulator/README.md.
 */
internal class ControlPort(port: Int, private val robots: () -> List<RobotHandle>) : AutoCloseable {
    private val server = ServerSocket().apply {
        reuseAddress = true
        bind(InetSocketAddress(InetAddress.getLoopbackAddress(), port), 16)
    }
    val port: Int = server.localPort
    @Volatile private var closed = false

    init {
        Thread({ loop() }, "emulator-control").apply { isDaemon = true; start() }
    }

    private fun loop() {
        while (!closed) {
            try {
                server.accept().use { s ->
                    val text = buildString { for (r in robots()) append(line(r.id, r.name, r.tcpPort)) }
                    s.getOutputStream().write(text.toByteArray(Charsets.US_ASCII))
                    s.getOutputStream().flush()
                }
            } catch (_: IOException) {
                if (closed) return
            }
        }
    }

    override fun close() {
        closed = true
        runCatching { server.close() }
    }

    companion object {
        fun line(id: Int, name: String, port: Int): String = "$id\t$name\t$port\n"
    }
}

package org.pocketbot.emulator.transport

import org.pocketbot.emulator.link.LinkConnection
import org.pocketbot.emulator.link.RobotLink
import java.io.IOException
import java.net.InetAddress
import java.net.InetSocketAddress
import java.net.ServerSocket
import java.net.Socket
import java.util.concurrent.LinkedBlockingQueue

/**
 * A robot reachable like a real one: a TCP server on 127.0.0.1 whose byte stream is the robot's serial link
 * (SLIP frames, through the link model). One host at a time; a new connection takes the robot over.
 */
internal class TcpEndpoint(private val link: RobotLink, port: Int, private val label: String) : AutoCloseable {
    private val server = ServerSocket().apply {
        reuseAddress = true
        bind(InetSocketAddress(InetAddress.getLoopbackAddress(), port), 8)
    }
    val port: Int = server.localPort
    @Volatile private var closed = false
    @Volatile private var current: Connection? = null

    init {
        Thread({ acceptLoop() }, "emulator-tcp-$label").apply { isDaemon = true; start() }
    }

    private fun acceptLoop() {
        while (!closed) {
            val socket = try { server.accept() } catch (e: IOException) { if (closed) return else continue }
            socket.tcpNoDelay = true
            val c = Connection(socket)
            try {
                link.attach(c)
            } catch (e: IllegalStateException) {
                socket.close() // link is down: the robot is out of range
                continue
            }
            current = c
            c.start()
        }
    }

    override fun close() {
        closed = true
        runCatching { server.close() }
        current?.let { it.shutdown(); link.detach(it) }
    }

    private inner class Connection(private val socket: Socket) : LinkConnection {
        private val out = LinkedBlockingQueue<ByteArray>()
        @Volatile private var open = true

        fun start() {
            Thread({ readLoop() }, "emulator-tcp-$label-rx").apply { isDaemon = true; start() }
            Thread({ writeLoop() }, "emulator-tcp-$label-tx").apply { isDaemon = true; start() }
        }

        private fun readLoop() {
            val buf = ByteArray(4096)
            try {
                val input = socket.getInputStream()
                while (open) {
                    val n = input.read(buf)
                    if (n < 0) break
                    if (n > 0) link.hostSend(buf.copyOf(n))
                }
            } catch (_: IOException) {
            } finally {
                shutdown(); link.detach(this)
            }
        }

        private fun writeLoop() {
            try {
                val output = socket.getOutputStream()
                while (open) {
                    val chunk = out.poll(200, java.util.concurrent.TimeUnit.MILLISECONDS) ?: continue
                    if (chunk.isEmpty()) break
                    output.write(chunk)
                    output.flush()
                }
            } catch (_: IOException) {
            } finally {
                shutdown(); link.detach(this)
            }
        }

        override fun onBytes(bytes: ByteArray) { if (open) out.add(bytes) }

        override fun onLinkLost(reason: String) { shutdown() }

        fun shutdown() {
            if (!open) return
            open = false
            out.add(ByteArray(0))
            runCatching { socket.close() }
        }
    }
}

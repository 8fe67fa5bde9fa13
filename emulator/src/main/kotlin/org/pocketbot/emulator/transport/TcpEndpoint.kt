package org.pocketbot.emulator.transport

import org.pocketbot.emulator.link.LinkConnection
import org.pocketbot.emulator.link.RobotLink
import java.io.IOException
import java.net.InetAddress
import java.net.InetSocketAddress
import java.net.Socket
import java.util.concurrent.LinkedBlockingQueue

/**
 * A robot reachable like a real one: a TCP server on [listen] (see [ListenAddress]) whose byte stream is the robot's
 * serial link (SLIP frames, through the link model). One host at a time; a new connection takes the robot over.
 */
internal class TcpEndpoint(private val link: RobotLink, listen: InetAddress, port: Int, private val label: String) : AutoCloseable {
    @Volatile private var current: Connection? = null
    private val acceptor = Acceptor(listen, port, backlog = 8, name = "emulator-tcp-$label") { socket -> attach(socket) }
    val port: Int = acceptor.port

    /** The host connected now, or null. */
    val client: InetSocketAddress? get() = current?.takeIf { it.isOpen }?.remote

    private fun attach(socket: Socket) {
        socket.tcpNoDelay = true
        val c = Connection(socket)
        // Known before the link drops the host it had, which may ask who holds the robot now.
        val before = current
        current = c
        try {
            link.attach(c)
        } catch (e: IllegalStateException) {
            current = before
            socket.close() // link is down: the robot is out of range
            return
        }
        c.start()
    }

    override fun close() {
        acceptor.close()
        current?.let { it.shutdown(); link.detach(it) }
    }

    private inner class Connection(private val socket: Socket) : LinkConnection {
        private val out = LinkedBlockingQueue<ByteArray>()
        @Volatile private var open = true
        val remote: InetSocketAddress? = socket.remoteSocketAddress as? InetSocketAddress
        val isOpen: Boolean get() = open

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

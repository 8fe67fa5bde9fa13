package org.pocketbot.emulator.transport

import org.pocketbot.emulator.link.LinkConnection
import org.pocketbot.emulator.link.NoFreeLinkException
import org.pocketbot.emulator.link.RobotLink
import org.pocketbot.emulator.link.RobotLinks
import org.pocketbot.protocol.Error
import org.pocketbot.protocol.ErrorCode
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Slip
import java.io.IOException
import java.net.InetAddress
import java.net.InetSocketAddress
import java.net.Socket
import java.util.concurrent.CopyOnWriteArrayList
import java.util.concurrent.LinkedBlockingQueue

/**
 * A robot reachable like a real one: a TCP server on [listen] (see [ListenAddress]) whose byte stream is one of the
 * robot's serial links (SLIP frames, through the link model). Every client is a host of its own on a link of its own;
 * when the robot has no free link left, the client gets an `error` of code `no_free_link` (detail: how many links the
 * robot has) and is closed.
 */
internal class TcpEndpoint(private val links: RobotLinks, listen: InetAddress, port: Int, private val label: String) : AutoCloseable {
    private val connections = CopyOnWriteArrayList<Connection>()
    private val acceptor = Acceptor(listen, port, backlog = 8, name = "emulator-tcp-$label") { socket -> attach(socket) }
    val port: Int = acceptor.port

    /** The hosts connected now, in the order they came. */
    val clients: List<InetSocketAddress> get() = connections.filter { it.isOpen }.mapNotNull { it.remote }

    private fun attach(socket: Socket) {
        socket.tcpNoDelay = true
        val c = Connection(socket)
        // Listed before it is attached: a host that asks who holds the robot finds itself.
        connections += c
        val link = try {
            links.attach(c)
        } catch (e: NoFreeLinkException) {
            connections -= c
            refuse(socket, e.links)
            return
        } catch (e: IllegalStateException) {
            connections -= c
            socket.close() // the link is down: the robot is out of range
            return
        }
        c.start(link)
    }

    /** The answer of a robot whose links are all in use, then the connection closes. */
    private fun refuse(socket: Socket, links: Int) {
        try {
            socket.use {
                it.getOutputStream().write(Slip.encode(Frames.encode(Error(ErrorCode.NO_FREE_LINK.code, 0, 0, links), 0)))
                it.getOutputStream().flush()
                it.shutdownOutput()
            }
        } catch (_: IOException) {
        }
    }

    override fun close() {
        acceptor.close()
        for (c in connections) c.shutdown()
    }

    private inner class Connection(private val socket: Socket) : LinkConnection {
        private val out = LinkedBlockingQueue<ByteArray>()
        @Volatile private var open = true
        private lateinit var link: RobotLink
        val remote: InetSocketAddress? = socket.remoteSocketAddress as? InetSocketAddress
        val isOpen: Boolean get() = open

        fun start(link: RobotLink) {
            this.link = link
            Thread({ readLoop() }, "emulator-tcp-$label-${link.index}-rx").apply { isDaemon = true; start() }
            Thread({ writeLoop() }, "emulator-tcp-$label-${link.index}-tx").apply { isDaemon = true; start() }
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
                shutdown()
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
                shutdown()
            }
        }

        override fun onBytes(bytes: ByteArray) { if (open) out.add(bytes) }

        override fun onLinkLost(reason: String) { shutdown() }

        /** Closes the socket; the host's bytes already read still reach the robot, then the firmware is told it left. */
        fun shutdown() {
            if (!open) return
            open = false
            connections -= this
            if (::link.isInitialized) link.detach(this)
            out.add(ByteArray(0))
            runCatching { socket.close() }
        }
    }
}

package org.pocketbot.emulator.bluetooth

import org.pocketbot.emulator.link.LinkConnection
import org.pocketbot.emulator.link.RobotLink
import java.io.IOException
import java.net.InetSocketAddress
import java.net.Socket
import java.util.concurrent.LinkedBlockingQueue
import java.util.concurrent.TimeUnit

/**
 * A robot's UART wired to a Bluetooth controller that speaks H4 on a TCP endpoint (a virtual controller of
 * [VirtualBluetooth], or Bumble's HCI bridge in front of a USB dongle): what the firmware sends goes to the
 * controller, what the controller sends goes into the robot's UART through the link model (baud rate, faults).
 *
 * A UART cannot be unplugged: when the TCP connection breaks, or the link model takes the link down, it connects
 * again as soon as it can, and bytes meanwhile are lost as on a dead wire. [close] ends it.
 */
internal class H4Uart(private val link: RobotLink, private val controller: InetSocketAddress, label: String) : AutoCloseable {
    @Volatile private var closed = false
    @Volatile private var socket: Socket? = null
    private val out = LinkedBlockingQueue<ByteArray>()

    /** The link's side: bytes the firmware sent reach [onBytes] on the stepping thread, which must not block. */
    private val connection = object : LinkConnection {
        override fun onBytes(bytes: ByteArray) { out.add(bytes) }
        override fun onLinkLost(reason: String) { runCatching { socket?.close() } }
    }

    // Last: the thread uses everything above.
    private val thread = Thread({ run() }, "emulator-h4-$label").apply { isDaemon = true; start() }

    private fun run() {
        while (!closed) {
            try {
                Socket().use { s ->
                    s.tcpNoDelay = true
                    s.connect(controller, CONNECT_TIMEOUT_MS)
                    socket = s
                    out.clear()
                    check(link.settings.connected && link.tryAttach(connection)) { "the link is down" }
                    val writer = Thread({ writeLoop(s) }, "${Thread.currentThread().name}-tx").apply { isDaemon = true; start() }
                    try {
                        val input = s.getInputStream()
                        val buf = ByteArray(4096)
                        while (!closed) {
                            val n = input.read(buf)
                            if (n < 0) break
                            if (n > 0) link.hostSend(buf.copyOf(n))
                        }
                    } finally {
                        link.detach(connection)
                        out.add(STOP)
                        writer.join(1000)
                    }
                }
            } catch (_: IOException) {
            } catch (_: IllegalStateException) { // the link model has the link down, or still drains the last wire's bytes
            }
            socket = null
            if (!closed) Thread.sleep(RETRY_MS)
        }
    }

    private fun writeLoop(s: Socket) {
        try {
            val output = s.getOutputStream()
            while (true) {
                val chunk = out.poll(200, TimeUnit.MILLISECONDS) ?: if (closed || s.isClosed) return else continue
                if (chunk === STOP) return
                output.write(chunk)
                output.flush()
            }
        } catch (_: IOException) {
            runCatching { s.close() }
        }
    }

    override fun close() {
        closed = true
        runCatching { socket?.close() }
        thread.join(2000)
    }

    private companion object {
        val STOP = ByteArray(0)
        const val CONNECT_TIMEOUT_MS = 2000
        const val RETRY_MS = 50L
    }
}

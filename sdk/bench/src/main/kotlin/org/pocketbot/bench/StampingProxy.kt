package org.pocketbot.bench

import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder
import java.net.InetAddress
import java.net.InetSocketAddress
import java.net.ServerSocket
import java.net.Socket
import java.util.concurrent.ConcurrentHashMap

/**
 * A TCP relay between the SDK and an emulator robot's endpoint that notes, for every state frame it hands to the SDK's
 * socket, the moment the frame's last byte was written (System.nanoTime), keyed by the robot time in the frame. So the
 * host-side latency is measured through the SDK's real TcpTransport, with no hook in it: from the last byte at the
 * socket to the StateFlow emission.
 */
class StampingProxy(private val robotPort: Int) : AutoCloseable {
    private val server = ServerSocket(0, 1, InetAddress.getLoopbackAddress())
    val port: Int get() = server.localPort
    val arrivals = ConcurrentHashMap<Long, Long>()
    @Volatile private var closed = false

    init {
        Thread({ acceptLoop() }, "proxy-$robotPort").apply { isDaemon = true; start() }
    }

    private fun acceptLoop() {
        while (!closed) {
            val host = runCatching { server.accept() }.getOrNull() ?: return
            val robot = Socket().apply { tcpNoDelay = true; connect(InetSocketAddress(InetAddress.getLoopbackAddress(), robotPort)) }
            host.tcpNoDelay = true
            Thread({ copy(host, robot) }, "proxy-up").apply { isDaemon = true; start() }
            Thread({ stampDown(robot, host) }, "proxy-down").apply { isDaemon = true; start() }
        }
    }

    private fun copy(from: Socket, to: Socket) {
        val buf = ByteArray(4096)
        runCatching {
            while (true) {
                val n = from.getInputStream().read(buf)
                if (n < 0) break
                to.getOutputStream().write(buf, 0, n)
            }
        }
        runCatching { to.close() }
        runCatching { from.close() }
    }

    /** Robot to host, a whole frame per write: each state frame is stamped right after its write returned. */
    private fun stampDown(from: Socket, to: Socket) {
        val buf = ByteArray(4096)
        val decoder = SlipDecoder()
        val out = to.getOutputStream()
        runCatching {
            while (true) {
                val n = from.getInputStream().read(buf)
                if (n < 0) break
                decoder.feed(buf, 0, n) { frame ->
                    out.write(Slip.encode(frame))
                    val now = System.nanoTime()
                    val type = frame[0].toInt()
                    if ((type == 2 || type == 3) && frame.size >= 7) {
                        val t = (frame[3].toLong() and 0xFF) or ((frame[4].toLong() and 0xFF) shl 8) or
                            ((frame[5].toLong() and 0xFF) shl 16) or ((frame[6].toLong() and 0xFF) shl 24)
                        arrivals[t] = now
                    }
                }
            }
        }
        runCatching { to.close() }
        runCatching { from.close() }
    }

    override fun close() {
        closed = true
        runCatching { server.close() }
    }
}

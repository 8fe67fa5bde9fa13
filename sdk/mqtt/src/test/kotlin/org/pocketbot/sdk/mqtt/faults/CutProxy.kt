package org.pocketbot.sdk.mqtt.faults

import java.io.Closeable
import java.net.InetAddress
import java.net.ServerSocket
import java.net.Socket
import java.util.concurrent.CopyOnWriteArrayList
import kotlin.concurrent.thread

/**
 * A TCP forwarder on a free loopback port to [targetPort], that a test cuts like a pulled cable: [cut] resets every
 * connection through it (no MQTT DISCONNECT goes out, so the broker publishes the client's last will) and refuses new
 * ones until [restore]. Bytes pass unchanged, TLS included.
 */
class CutProxy(private val targetPort: Int) : Closeable {
    private val server = ServerSocket(0, 50, InetAddress.getLoopbackAddress())
    private val sockets = CopyOnWriteArrayList<Socket>()

    @Volatile private var open = true

    @Volatile private var closed = false

    val port: Int get() = server.localPort

    init {
        thread(name = "cut-proxy-$port", isDaemon = true) {
            while (!closed) {
                val client = runCatching { server.accept() }.getOrNull() ?: break
                if (!open) {
                    reset(client)
                    continue
                }
                val upstream = runCatching { Socket(InetAddress.getLoopbackAddress(), targetPort) }.getOrElse {
                    reset(client)
                    null
                } ?: continue
                for (s in listOf(client, upstream)) {
                    s.tcpNoDelay = true
                    sockets += s
                }
                pump(client, upstream)
                pump(upstream, client)
            }
        }
    }

    /** Resets every connection through the proxy and refuses new ones. */
    fun cut() {
        open = false
        sockets.forEach(::reset)
        sockets.clear()
    }

    /** Accepts and forwards connections again. */
    fun restore() {
        open = true
    }

    override fun close() {
        closed = true
        cut()
        server.close()
    }

    private fun pump(from: Socket, to: Socket) = thread(name = "cut-proxy-pump", isDaemon = true) {
        val buffer = ByteArray(16 * 1024)
        try {
            val input = from.getInputStream()
            val output = to.getOutputStream()
            while (true) {
                val n = input.read(buffer)
                if (n < 0) break
                output.write(buffer, 0, n)
            }
        } catch (_: java.io.IOException) {
            // cut, or the other side closed
        }
        reset(from)
        reset(to)
    }

    /** Closes with a TCP reset, as a dead host's kernel or a broken path leaves it: no orderly goodbye. */
    private fun reset(s: Socket) {
        runCatching { s.setSoLinger(true, 0) }
        runCatching { s.close() }
    }
}

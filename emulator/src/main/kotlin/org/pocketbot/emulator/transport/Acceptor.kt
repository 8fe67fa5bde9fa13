package org.pocketbot.emulator.transport

import java.io.IOException
import java.net.InetAddress
import java.net.InetSocketAddress
import java.net.ServerSocket
import java.net.Socket

/**
 * A listening TCP socket on [listen]:[port] (0: any free port) whose thread hands each connection to [serve].
 *
 * When [close] returns, the accepting thread has ended: no connection is served after it. Closing a
 * [ServerSocket] only signals a thread blocked in `accept`, and a connection that arrives in that window is still
 * accepted; without the join a client could be answered by an endpoint its emulator had already stopped.
 */
internal class Acceptor(
    listen: InetAddress,
    port: Int,
    backlog: Int,
    name: String,
    private val serve: (Socket) -> Unit,
) : AutoCloseable {
    private val server = ServerSocket().apply {
        reuseAddress = true
        bind(InetSocketAddress(listen, port), backlog)
    }
    val port: Int = server.localPort
    @Volatile private var closed = false
    private val thread = Thread({ loop() }, name).apply { isDaemon = true; start() }

    private fun loop() {
        while (!closed) {
            val socket = try { server.accept() } catch (_: IOException) { continue }
            if (closed) { runCatching { socket.close() }; return }
            try { serve(socket) } catch (_: IOException) { runCatching { socket.close() } }
        }
    }

    override fun close() {
        closed = true
        runCatching { server.close() }
        if (Thread.currentThread() !== thread) thread.join(JOIN_TIMEOUT_MS)
    }

    private companion object {
        /** A connection being served is a few lines or an attach; far longer means something hangs: do not hang too. */
        const val JOIN_TIMEOUT_MS = 5_000L
    }
}

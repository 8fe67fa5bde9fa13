package org.pocketbot.sdk.transport

import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.channels.ClosedReceiveChannelException

/**
 * An in-memory link for tests: what the "robot" side pushes with [robotSends] comes out of [hostStream]'s
 * read in exactly those chunks; what the host writes is collected in [fromHost].
 */
internal class MemoryPipe {
    private val toHost = Channel<ByteArray>(Channel.UNLIMITED)
    val fromHost = Channel<ByteArray>(Channel.UNLIMITED)
    var writeFailure: Throwable? = null
    var closeCount = 0
        private set

    fun robotSends(vararg chunks: ByteArray) {
        for (c in chunks) check(toHost.trySend(c).isSuccess) { "pipe to host is closed" }
    }

    /** The robot side closes the link cleanly: the host's read sees end of stream. */
    fun robotHangsUp() { toHost.close() }

    /** The link breaks: the host's pending read throws [cause]. */
    fun linkBreaks(cause: Throwable) { toHost.close(cause) }

    /** Everything the host wrote so far, as one array. */
    fun hostBytes(): ByteArray {
        var all = ByteArray(0)
        while (true) all += fromHost.tryReceive().getOrNull() ?: break
        return all
    }

    val hostStream: ByteStream = object : ByteStream {
        private var pending = ByteArray(0)
        private var pos = 0

        override suspend fun read(buffer: ByteArray, offset: Int, length: Int): Int {
            if (pos == pending.size) {
                pending = try {
                    toHost.receive()
                } catch (_: ClosedReceiveChannelException) {
                    return -1
                }
                pos = 0
            }
            val n = minOf(length, pending.size - pos)
            pending.copyInto(buffer, offset, pos, pos + n)
            pos += n
            return n
        }

        override suspend fun write(bytes: ByteArray) {
            writeFailure?.let { throw it }
            fromHost.send(bytes.copyOf())
        }

        override fun close() {
            closeCount++
            toHost.close()
        }
    }
}

internal class FakeIoException(message: String) : Exception(message)

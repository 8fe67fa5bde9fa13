package org.pocketbot.sdk.transport

import kotlin.concurrent.atomics.AtomicReference
import kotlin.concurrent.atomics.ExperimentalAtomicApi
import kotlin.coroutines.CoroutineContext
import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineName
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.channels.ReceiveChannel
import kotlinx.coroutines.currentCoroutineContext
import kotlinx.coroutines.ensureActive
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import kotlinx.coroutines.sync.Mutex
import kotlinx.coroutines.sync.withLock
import org.pocketbot.protocol.ProtocolError

/**
 * A frame [Transport] over any [ByteStream], with the framing its subclass puts on the stream: [SlipStreamTransport]
 * (SLIP, every PocketBot stream link) or [LengthPrefixedStreamTransport] (a length before each frame, for links that
 * carry frames whole, such as the Bluetooth gateway's L2CAP endpoint).
 *
 * - One coroutine reads the stream, splits it into frames however it was chunked, and delivers them to
 *   [incoming] in order. When [incoming] is full the reader waits, so a slow consumer slows the link down
 *   instead of losing frames.
 * - Broken framing (an invalid SLIP escape, a frame longer than `maxFrame`) drops that frame and counts it in
 *   [droppedFrames]; the stream goes on with the next frame. Frame contents are not checked here: that is
 *   [org.pocketbot.protocol.Frames.decode]'s job.
 * - When the stream ends or fails (the robot switched off, the socket or tty went away), the link is lost:
 *   [incoming] is closed with a [TransportLostException], the stream is closed and [send] throws
 *   [TransportLostException] from then on.
 * - [close] closes [incoming] normally (frames already received can still be read), stops the reader and
 *   closes the stream. It is idempotent and safe to call from any thread.
 */
@OptIn(ExperimentalAtomicApi::class)
public abstract class ByteStreamTransport internal constructor(
    final override val address: String,
    private val stream: ByteStream,
    context: CoroutineContext,
    incomingCapacity: Int,
    private val framing: StreamFraming,
) : Transport {
    private val frames = Channel<ByteArray>(incomingCapacity)
    private val drops = MutableStateFlow(DroppedFrames())
    private val lastError = MutableStateFlow<ProtocolError?>(null)
    private val writeLock = Mutex()

    /** null while open, then [CLOSED] or the [TransportLostException] that ended the link. */
    private val ending = AtomicReference<Any?>(null)
    private val scope = CoroutineScope(context + SupervisorJob(context[Job]) + CoroutineName("stream $address"))

    final override val incoming: ReceiveChannel<ByteArray> get() = frames

    /** Frames the decoder dropped (broken framing, longer than `maxFrame`), since the transport was opened. */
    final override val droppedFrames: StateFlow<DroppedFrames> = drops.asStateFlow()

    /** Why the latest frame was dropped by the decoder, or null while none was. */
    public val lastFramingError: StateFlow<ProtocolError?> = lastError.asStateFlow()

    /** True until [close] is called or the link is lost. */
    public val isOpen: Boolean get() = ending.load() == null

    init {
        scope.launch { readLoop(framing.decoder()) }
    }

    private suspend fun readLoop(decoder: StreamDecoder) {
        val buffer = ByteArray(READ_CHUNK)
        val batch = ArrayList<ByteArray>()
        try {
            while (true) {
                val n = stream.read(buffer, 0, buffer.size)
                if (n < 0) {
                    lose(TransportLostException("$address: the link was closed by the other end"))
                    return
                }
                decoder.feed(buffer, n, ::countFramingError) { batch.add(it) }
                for (frame in batch) frames.send(frame)
                batch.clear()
            }
        } catch (e: Throwable) {
            if (ending.load() != null) {
                if (e is CancellationException) throw e
                return
            }
            lose(TransportLostException("$address: ${describe(e)}", e))
            if (e is CancellationException) throw e
        }
    }

    private fun countFramingError(error: ProtocolError) {
        drops.update {
            if (error is ProtocolError.TooLong) DroppedFrames(it.tooLong + 1, it.badFraming) else DroppedFrames(it.tooLong, it.badFraming + 1)
        }
        lastError.value = error
    }

    /** Sends one frame, framed for the stream. Concurrent calls do not interleave their bytes. Suspends while writing. */
    final override suspend fun send(frame: ByteArray) {
        val bytes = framing.encode(frame)
        writeLock.withLock {
            failIfEnded()
            try {
                stream.write(bytes)
            } catch (e: Throwable) {
                currentCoroutineContext().ensureActive()
                failIfEnded()
                val lost = TransportLostException("$address: sending failed: ${describe(e)}", e)
                lose(lost)
                throw lost
            }
        }
    }

    final override fun close() {
        if (!ending.compareAndSet(null, CLOSED)) return
        frames.close()
        scope.cancel()
        stream.close()
    }

    private fun lose(cause: TransportLostException) {
        if (!ending.compareAndSet(null, cause)) return
        frames.close(cause)
        stream.close()
        scope.cancel()
    }

    private fun failIfEnded() {
        when (val end = ending.load()) {
            null -> return
            is TransportLostException -> throw TransportLostException(end.message ?: address, end)
            else -> throw TransportLostException("$address: the transport is closed")
        }
    }

    override fun toString(): String = "${this::class.simpleName}($address)"

    private companion object {
        const val READ_CHUNK = 1024
        val CLOSED = Any()

        fun describe(e: Throwable): String = e.message ?: e::class.simpleName ?: "error"
    }
}

/** How frames sit in a byte stream: a decoder per stream splits what arrives into frames; [encode] wraps one. */
internal interface StreamFraming {
    fun decoder(): StreamDecoder
    fun encode(frame: ByteArray): ByteArray
}

/** Splits one stream's bytes into frames, however they were chunked; reports each frame it had to drop. */
internal fun interface StreamDecoder {
    fun feed(bytes: ByteArray, length: Int, onError: (ProtocolError) -> Unit, onFrame: (ByteArray) -> Unit)
}

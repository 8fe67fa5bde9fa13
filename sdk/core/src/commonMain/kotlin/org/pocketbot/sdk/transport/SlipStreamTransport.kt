package org.pocketbot.sdk.transport

import kotlin.concurrent.atomics.AtomicReference
import kotlin.concurrent.atomics.ExperimentalAtomicApi
import kotlin.coroutines.CoroutineContext
import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineName
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
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
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.ProtocolError
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder

/**
 * A frame [Transport] over any [ByteStream]: SLIP (RFC 1055) on the wire, whole frames in [incoming] and [send].
 * The TCP and serial transports are this class over a socket or a port; a Bluetooth RFCOMM socket on Android is
 * one more [ByteStream].
 *
 * - One coroutine reads the stream, splits it into frames however it was chunked, and delivers them to
 *   [incoming] in order. When [incoming] is full the reader waits, so a slow consumer slows the link down
 *   instead of losing frames.
 * - Broken SLIP (an invalid escape, a frame longer than `maxFrame`) drops that frame and counts it in
 *   [droppedFrames]; the stream goes on at the next END byte. Frame contents are not checked here: that is
 *   [Frames.decode]'s job.
 * - When the stream ends or fails (the robot switched off, the socket or tty went away), the link is lost:
 *   [incoming] is closed with a [TransportLostException], the stream is closed and [send] throws
 *   [TransportLostException] from then on.
 * - [close] closes [incoming] normally (frames already received can still be read), stops the reader and
 *   closes the stream. It is idempotent and safe to call from any thread.
 *
 * ```
 * val transport = SlipStreamTransport("pipe:test", myByteStream)
 * transport.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, session), seq = 1))
 * val reply = Frames.decode(transport.incoming.receive())
 * transport.close()
 * ```
 *
 * @param address where the robot is, see [Transport.address].
 * @param stream the byte stream; this transport owns it from now on and closes it.
 * @param context where the reader coroutine runs, [Dispatchers.Default] unless given. A [Job] in it becomes the
 *   parent of the reader: cancelling that job loses the link.
 * @param maxFrame the longest frame accepted, in bytes (SLIP escapes not counted).
 * @param incomingCapacity how many received frames [incoming] buffers before the reader waits.
 */
@OptIn(ExperimentalAtomicApi::class)
public open class SlipStreamTransport(
    final override val address: String,
    private val stream: ByteStream,
    context: CoroutineContext = Dispatchers.Default,
    maxFrame: Int = Frames.MAX_FRAME,
    incomingCapacity: Int = DEFAULT_INCOMING_CAPACITY,
) : Transport {
    private val frames = Channel<ByteArray>(incomingCapacity)
    private val drops = MutableStateFlow(DroppedFrames())
    private val lastError = MutableStateFlow<ProtocolError?>(null)
    private val writeLock = Mutex()

    /** null while open, then [CLOSED] or the [TransportLostException] that ended the link. */
    private val ending = AtomicReference<Any?>(null)
    private val scope = CoroutineScope(context + SupervisorJob(context[Job]) + CoroutineName("slip $address"))

    final override val incoming: ReceiveChannel<ByteArray> get() = frames

    /** Frames the SLIP decoder dropped (broken framing, longer than `maxFrame`), since the transport was opened. */
    final override val droppedFrames: StateFlow<DroppedFrames> = drops.asStateFlow()

    /** Why the latest frame was dropped by the SLIP decoder, or null while none was. */
    public val lastFramingError: StateFlow<ProtocolError?> = lastError.asStateFlow()

    /** True until [close] is called or the link is lost. */
    public val isOpen: Boolean get() = ending.load() == null

    init {
        require(maxFrame > 0) { "maxFrame must be positive, was $maxFrame" }
        scope.launch { readLoop(SlipDecoder(maxFrame)) }
    }

    private suspend fun readLoop(decoder: SlipDecoder) {
        val buffer = ByteArray(READ_CHUNK)
        val batch = ArrayList<ByteArray>()
        try {
            while (true) {
                val n = stream.read(buffer, 0, buffer.size)
                if (n < 0) {
                    lose(TransportLostException("$address: the link was closed by the other end"))
                    return
                }
                decoder.feed(buffer, 0, n, onError = ::countFramingError) { batch.add(it) }
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

    /** Sends one frame, SLIP-encoded. Concurrent calls do not interleave their bytes. Suspends while writing. */
    final override suspend fun send(frame: ByteArray) {
        val bytes = Slip.encode(frame)
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

    public companion object {
        /** Default capacity of [incoming], in frames. */
        public const val DEFAULT_INCOMING_CAPACITY: Int = 256

        private const val READ_CHUNK = 1024
        private val CLOSED = Any()

        private fun describe(e: Throwable): String = e.message ?: e::class.simpleName ?: "error"
    }
}

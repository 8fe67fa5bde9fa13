package org.pocketbot.sdk.transport

import kotlin.coroutines.CoroutineContext
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.Job
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder

/**
 * A frame [Transport] over any [ByteStream]: SLIP (RFC 1055) on the wire, whole frames in [incoming] and [send].
 * The TCP and serial transports are this class over a socket or a port; a Bluetooth RFCOMM socket on Android is
 * one more [ByteStream]. Reading, dropped frames, a lost link and [close] behave as [ByteStreamTransport] says; a
 * dropped frame costs the bytes up to the next END.
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
public open class SlipStreamTransport(
    address: String,
    stream: ByteStream,
    context: CoroutineContext = Dispatchers.Default,
    maxFrame: Int = Frames.MAX_FRAME,
    incomingCapacity: Int = DEFAULT_INCOMING_CAPACITY,
) : ByteStreamTransport(address, stream, context, incomingCapacity, SlipFraming(maxFrame)) {
    public companion object {
        /** Default capacity of [incoming], in frames. */
        public const val DEFAULT_INCOMING_CAPACITY: Int = 256
    }
}

private class SlipFraming(private val maxFrame: Int) : StreamFraming {
    init {
        require(maxFrame > 0) { "maxFrame must be positive, was $maxFrame" }
    }

    override fun decoder(): StreamDecoder {
        val slip = SlipDecoder(maxFrame)
        return StreamDecoder { bytes, length, onError, onFrame -> slip.feed(bytes, 0, length, onError, onFrame) }
    }

    override fun encode(frame: ByteArray): ByteArray = Slip.encode(frame)
}

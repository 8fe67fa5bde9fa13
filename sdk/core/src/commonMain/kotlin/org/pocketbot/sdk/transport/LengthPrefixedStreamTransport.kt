package org.pocketbot.sdk.transport

import kotlin.coroutines.CoroutineContext
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.Job
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.ProtocolError

/**
 * A frame [Transport] over a [ByteStream] that carries frames whole, each after its length: 2 bytes, little-endian,
 * then the frame (header, payload, CRC), no SLIP. This is how the Bluetooth gateway (emulator/bluetooth) offers a
 * robot's framed L2CAP channel on TCP, one L2CAP SDU per frame. Reading, a lost link and [close] behave as
 * [ByteStreamTransport] says; a frame longer than `maxFrame` is skipped whole and counted in
 * [DroppedFrames.tooLong].
 *
 * @param address where the robot is, see [Transport.address].
 * @param stream the byte stream; this transport owns it from now on and closes it.
 * @param context where the reader coroutine runs, [Dispatchers.Default] unless given. A [Job] in it becomes the
 *   parent of the reader: cancelling that job loses the link.
 * @param maxFrame the longest frame accepted, in bytes.
 * @param incomingCapacity how many received frames [incoming] buffers before the reader waits.
 */
public open class LengthPrefixedStreamTransport(
    address: String,
    stream: ByteStream,
    context: CoroutineContext = Dispatchers.Default,
    maxFrame: Int = Frames.MAX_FRAME,
    incomingCapacity: Int = SlipStreamTransport.DEFAULT_INCOMING_CAPACITY,
) : ByteStreamTransport(address, stream, context, incomingCapacity, LengthPrefixFraming(maxFrame)) {
    public companion object {
        /** Bytes of the length before each frame. */
        public const val PREFIX_SIZE: Int = 2
    }
}

private class LengthPrefixFraming(private val maxFrame: Int) : StreamFraming {
    init {
        require(maxFrame in 1..0xFFFF) { "maxFrame must be 1..65535, was $maxFrame" }
    }

    override fun encode(frame: ByteArray): ByteArray {
        require(frame.size <= 0xFFFF) { "a frame of ${frame.size} bytes has no 2-byte length" }
        val out = ByteArray(LengthPrefixedStreamTransport.PREFIX_SIZE + frame.size)
        out[0] = frame.size.toByte()
        out[1] = (frame.size shr 8).toByte()
        frame.copyInto(out, LengthPrefixedStreamTransport.PREFIX_SIZE)
        return out
    }

    override fun decoder(): StreamDecoder = object : StreamDecoder {
        private val prefix = ByteArray(LengthPrefixedStreamTransport.PREFIX_SIZE)
        private var prefixHave = 0
        private var frame: ByteArray? = null  // the frame being filled, or null while it is skipped or between frames
        private var have = 0
        private var need = 0

        override fun feed(bytes: ByteArray, length: Int, onError: (ProtocolError) -> Unit, onFrame: (ByteArray) -> Unit) {
            var i = 0
            while (i < length) {
                if (prefixHave < prefix.size) {
                    prefix[prefixHave++] = bytes[i++]
                    if (prefixHave == prefix.size) start((prefix[0].toInt() and 0xFF) or ((prefix[1].toInt() and 0xFF) shl 8), onError)
                } else {
                    val n = minOf(need - have, length - i)
                    frame?.let { bytes.copyInto(it, have, i, i + n) }
                    have += n; i += n
                }
                if (prefixHave == prefix.size && have == need) {
                    frame?.let(onFrame)
                    prefixHave = 0; frame = null
                }
            }
        }

        private fun start(size: Int, onError: (ProtocolError) -> Unit) {
            have = 0; need = size
            if (size > maxFrame) onError(ProtocolError.TooLong(size)) else frame = ByteArray(size)
        }
    }
}

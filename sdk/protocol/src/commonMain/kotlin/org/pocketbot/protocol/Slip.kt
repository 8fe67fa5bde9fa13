package org.pocketbot.protocol

/** SLIP (RFC 1055) framing for stream links: serial, Bluetooth RFCOMM, TCP. */
public object Slip {
    public const val END: Byte = 0xC0.toByte()
    public const val ESC: Byte = 0xDB.toByte()
    public const val ESC_END: Byte = 0xDC.toByte()
    public const val ESC_ESC: Byte = 0xDD.toByte()

    /** [frame] escaped and wrapped in END bytes (a leading END flushes line noise at the receiver). */
    public fun encode(frame: ByteArray): ByteArray {
        var escapes = 0
        for (b in frame) if (b == END || b == ESC) escapes++
        val out = ByteArray(frame.size + escapes + 2)
        var i = 0
        out[i++] = END
        for (b in frame) {
            when (b) {
                END -> { out[i++] = ESC; out[i++] = ESC_END }
                ESC -> { out[i++] = ESC; out[i++] = ESC_ESC }
                else -> out[i++] = b
            }
        }
        out[i] = END
        return out
    }
}

/**
 * Splits a SLIP byte stream into frames, however the stream was cut into chunks. Empty frames (END END) are
 * skipped silently; a frame longer than [maxFrame] is dropped and reported as [ProtocolError.TooLong], an invalid
 * escape as [ProtocolError.Framing]; decoding resumes at the next END. Not thread-safe: one per stream.
 *
 * The bytes before the stream's first END are skipped, not reported: a receiver that joins a stream while the other
 * side is sending (a host connecting to a robot that streams its state) first gets the tail of a frame it never had
 * the start of, and that frame was not lost on this link. No frame is lost by it either: [Slip.encode] and the
 * firmware begin every frame with an END.
 */
public class SlipDecoder(private val maxFrame: Int = Frames.MAX_FRAME) {
    private val buf = ByteArray(maxFrame)
    private var size = 0
    private var escaped = false
    private var broken: String? = null
    private var overflow = 0
    private var joined = false

    /** Feeds [length] bytes from [offset]; calls [onFrame] for each complete frame and [onError] for each dropped one. */
    public fun feed(
        bytes: ByteArray, offset: Int = 0, length: Int = bytes.size - offset,
        onError: (ProtocolError) -> Unit = {}, onFrame: (ByteArray) -> Unit,
    ) {
        for (i in offset until offset + length) {
            val b = bytes[i]
            if (!joined) {
                joined = b == Slip.END
                continue
            }
            if (b == Slip.END) {
                val reason = broken
                when {
                    overflow > 0 -> onError(ProtocolError.TooLong(maxFrame + overflow))
                    reason != null -> onError(ProtocolError.Framing(reason))
                    escaped -> onError(ProtocolError.Framing("frame ends inside an escape"))
                    size > 0 -> onFrame(buf.copyOf(size))
                }
                size = 0; escaped = false; broken = null; overflow = 0
                continue
            }
            if (overflow > 0) {
                if (b != Slip.ESC) overflow++
                continue
            }
            if (broken != null) continue
            val value = if (escaped) {
                escaped = false
                when (b) {
                    Slip.ESC_END -> Slip.END
                    Slip.ESC_ESC -> Slip.ESC
                    else -> { broken = "invalid escape 0x${(b.toInt() and 0xFF).toString(16)}"; continue }
                }
            } else if (b == Slip.ESC) {
                escaped = true; continue
            } else b
            if (size == maxFrame) { overflow = 1; continue }
            buf[size++] = value
        }
    }
}

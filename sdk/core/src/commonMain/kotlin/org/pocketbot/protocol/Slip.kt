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
 * skipped silently; an invalid escape or a frame longer than [maxFrame] drops that frame and reports a
 * [ProtocolError.Framing], after which decoding resumes at the next END. Not thread-safe: one per stream.
 */
public class SlipDecoder(private val maxFrame: Int = Frames.MAX_FRAME) {
    private val buf = ByteArray(maxFrame)
    private var size = 0
    private var escaped = false
    private var broken: String? = null

    /** Feeds [length] bytes from [offset]; calls [onFrame] for each complete frame and [onError] for each dropped one. */
    public fun feed(
        bytes: ByteArray, offset: Int = 0, length: Int = bytes.size - offset,
        onError: (ProtocolError.Framing) -> Unit = {}, onFrame: (ByteArray) -> Unit,
    ) {
        for (i in offset until offset + length) {
            val b = bytes[i]
            if (b == Slip.END) {
                val reason = broken
                when {
                    reason != null -> onError(ProtocolError.Framing(reason))
                    escaped -> onError(ProtocolError.Framing("frame ends inside an escape"))
                    size > 0 -> onFrame(buf.copyOf(size))
                }
                size = 0; escaped = false; broken = null
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
            if (size == maxFrame) { broken = "frame longer than $maxFrame bytes"; continue }
            buf[size++] = value
        }
    }
}

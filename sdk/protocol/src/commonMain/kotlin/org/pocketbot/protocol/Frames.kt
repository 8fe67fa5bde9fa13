package org.pocketbot.protocol

/**
 * Frames: `type, seq, length, payload, crc16` (see docs/protocol.md). Decoding takes any bytes and never throws:
 * what is wrong comes back as a [ProtocolError].
 */
public object Frames {
    /** Header bytes before the payload. */
    public const val HEADER_SIZE: Int = 3

    /** CRC bytes after the payload. */
    public const val CRC_SIZE: Int = 2

    /** The largest frame the protocol allows. */
    public const val MAX_FRAME: Int = HEADER_SIZE + ProtocolInfo.MAX_PAYLOAD + CRC_SIZE

    /** The frame carrying [packet] with sequence number [seq] (0..255). */
    public fun encode(packet: Packet, seq: Int): ByteArray {
        require(seq in 0..255) { "seq $seq is not a byte" }
        val length = payloadSizeOf(packet)
        // One right-sized array: header, payload encoded in place, CRC.
        val frame = ByteArray(HEADER_SIZE + length + CRC_SIZE)
        frame[0] = packet.type.toByte()
        frame[1] = seq.toByte()
        frame[2] = length.toByte()
        encodePayloadInto(packet, frame, HEADER_SIZE)
        val crc = Crc16.compute(frame, 0, HEADER_SIZE + length)
        frame[HEADER_SIZE + length] = crc.toByte()
        frame[HEADER_SIZE + length + 1] = (crc shr 8).toByte()
        return frame
    }

    /**
     * Decodes the payload of a packet of [type] ([length] bytes of [payload] from [offset], without frame header
     * or CRC), or null when the type is unknown or the bytes do not fit it. Never throws for any bytes.
     */
    public fun decodePayload(type: Int, payload: ByteArray, offset: Int = 0, length: Int = payload.size - offset): Packet? {
        if (offset < 0 || length < 0 || offset > payload.size - length) return null
        val spec = if (type in 0..255) PACKET_SPEC_BY_TYPE[type] else null
        if (spec == null || length < spec.minSize || length > spec.maxSize) return null
        return try {
            decodePacketPayload(type, payload, offset, offset + length)
        } catch (e: LengthMismatch) {
            null
        }
    }

    /** Checks and decodes one frame (without SLIP). */
    public fun decode(frame: ByteArray): FrameResult {
        if (frame.size < HEADER_SIZE + CRC_SIZE) return FrameResult.Failed(ProtocolError.TooShort(frame.size))
        if (frame.size > MAX_FRAME) return FrameResult.Failed(ProtocolError.TooLong(frame.size))
        val type = frame[0].toInt() and 0xFF
        val seq = frame[1].toInt() and 0xFF
        val length = frame[2].toInt() and 0xFF
        if (HEADER_SIZE + length + CRC_SIZE != frame.size) {
            return FrameResult.Failed(ProtocolError.BadLength(type, seq, length, frame.size))
        }
        val expected = Crc16.compute(frame, 0, HEADER_SIZE + length)
        val actual = (frame[frame.size - 2].toInt() and 0xFF) or ((frame[frame.size - 1].toInt() and 0xFF) shl 8)
        if (expected != actual) return FrameResult.Failed(ProtocolError.BadCrc(expected, actual))
        val spec = PACKET_SPEC_BY_TYPE[type] ?: return FrameResult.Failed(ProtocolError.UnknownType(type, seq))
        if (length < spec.minSize || length > spec.maxSize) {
            return FrameResult.Failed(ProtocolError.BadLength(type, seq, length, frame.size))
        }
        return try {
            FrameResult.Decoded(seq, decodePacketPayload(type, frame, HEADER_SIZE, HEADER_SIZE + length))
        } catch (e: LengthMismatch) {
            FrameResult.Failed(ProtocolError.BadLength(type, seq, length, frame.size))
        }
    }
}

/** The outcome of [Frames.decode]. */
public sealed interface FrameResult {
    /** A valid frame: its sequence number and packet. */
    public data class Decoded(val seq: Int, val packet: Packet) : FrameResult

    /** A frame that was dropped, and why. */
    public data class Failed(val error: ProtocolError) : FrameResult
}

/** What was wrong with received bytes. Each maps to the firmware's [ErrorCode]. */
public sealed class ProtocolError(public val code: ErrorCode, public val message: String) {
    override fun toString(): String = "${code.name.lowercase()}: $message"

    /** The CRC does not match: the frame was corrupted on the way. */
    public data class BadCrc(val expected: Int, val actual: Int) :
        ProtocolError(ErrorCode.BAD_CRC, "CRC 0x${actual.toString(16)} where 0x${expected.toString(16)} was expected")

    /** Fewer bytes than a header and a CRC. */
    public data class TooShort(val size: Int) : ProtocolError(ErrorCode.TOO_SHORT, "frame of $size bytes is too short")

    /** More bytes than the largest frame. */
    public data class TooLong(val size: Int) :
        ProtocolError(ErrorCode.TOO_LONG, "frame of $size bytes exceeds ${Frames.MAX_FRAME}")

    /** A packet type this side does not know: a different protocol version, or garbage. */
    public data class UnknownType(val type: Int, val seq: Int) : ProtocolError(ErrorCode.UNKNOWN_TYPE, "unknown packet type 0x${type.toString(16)}")

    /** The length byte disagrees with the frame or with what the type allows. */
    public data class BadLength(val type: Int, val seq: Int, val length: Int, val frameSize: Int) :
        ProtocolError(ErrorCode.BAD_LENGTH, "length $length does not fit packet type 0x${type.toString(16)} in a frame of $frameSize bytes")

    /** SLIP framing broke: an invalid escape, or a frame longer than the decoder accepts. */
    public data class Framing(val reason: String) : ProtocolError(ErrorCode.FRAMING, reason)
}

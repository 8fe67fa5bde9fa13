package org.pocketbot.protocol

import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertIs

// Float values exact in binary32: on Kotlin/JS a Float literal keeps double precision until it is encoded.
class FramesTest {
    private val frame = Frames.encode(MoveRotate(3, 90f, 0.125f), 9)

    private fun failure(bytes: ByteArray): ProtocolError = assertIs<FrameResult.Failed>(Frames.decode(bytes)).error

    @Test
    fun roundTrip() {
        assertEquals(FrameResult.Decoded(9, MoveRotate(3, 90f, 0.125f)), Frames.decode(frame))
    }

    @Test
    fun everySingleBitFlipIsDetected() {
        for (i in frame.indices) for (bit in 0 until 8) {
            val bad = frame.copyOf().also { it[i] = (it[i].toInt() xor (1 shl bit)).toByte() }
            assertIs<FrameResult.Failed>(Frames.decode(bad), "flip of bit $bit in byte $i went unnoticed")
        }
    }

    @Test
    fun swappedAndZeroedBytesThatASumMissesAreDetected() {
        val swapped = frame.copyOf().also { val t = it[3]; it[3] = it[4]; it[4] = t } // id bytes 03 00 -> 00 03
        assertIs<ProtocolError.BadCrc>(failure(swapped))
        val zeroed = Frames.encode(MoveStraight(0x0102, 1f, 1f), 1).also { it[3] = 0; it[4] = 3 }
        assertIs<ProtocolError.BadCrc>(failure(zeroed))
    }

    @Test
    fun shortFrames() {
        for (n in 0 until 5) assertIs<ProtocolError.TooShort>(failure(frame.copyOf(n)), "frame of $n bytes")
    }

    @Test
    fun truncatedFrameDisagreesWithItsLength() {
        assertIs<ProtocolError.BadLength>(failure(frame.copyOf(frame.size - 1)))
    }

    @Test
    fun overLongFrame() {
        assertIs<ProtocolError.TooLong>(failure(ByteArray(Frames.MAX_FRAME + 1)))
    }

    private fun frameOf(type: Int, payload: ByteArray, seq: Int = 5): ByteArray {
        val head = byteArrayOf(type.toByte(), seq.toByte(), payload.size.toByte()) + payload
        val crc = Crc16.compute(head)
        return head + byteArrayOf(crc.toByte(), (crc shr 8).toByte())
    }

    @Test
    fun unknownType() {
        val e = assertIs<ProtocolError.UnknownType>(failure(frameOf(0x7F, byteArrayOf(1, 2))))
        assertEquals(0x7F, e.type)
        assertEquals(5, e.seq)
    }

    @Test
    fun lengthThatDisagreesWithTheType() {
        assertIs<ProtocolError.BadLength>(failure(frameOf(MoveStraight.TYPE, ByteArray(MoveStraight.SIZE - 1))))
        assertIs<ProtocolError.BadLength>(failure(frameOf(MoveStraight.TYPE, ByteArray(MoveStraight.SIZE + 1))))
        // update_settings whose count says 5 bytes while 4 follow
        assertIs<ProtocolError.BadLength>(failure(frameOf(UpdateSettings.TYPE, byteArrayOf(0, 0, 5, 1, 2, 3, 4))))
    }

    @Test
    fun crcMatchesTheStandardCheckValue() {
        assertEquals(0x29B1, Crc16.compute("123456789".encodeToByteArray()))
    }
}

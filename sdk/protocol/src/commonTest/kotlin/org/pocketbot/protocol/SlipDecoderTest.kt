package org.pocketbot.protocol

import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals
import kotlin.test.assertTrue

class SlipDecoderTest {
    private val frames = listOf(
        Frames.encode(MoveStraight(7, 0.125f, 0.25f), 1),
        Frames.encode(UpdateSettings(3, byteArrayOf(0xC0.toByte(), 0xDB.toByte(), 1)), 2),
        Frames.encode(Heartbeat, 0),
    )
    private val stream = frames.fold(ByteArray(0)) { acc, f -> acc + Slip.encode(f) }

    private fun decodeChunks(chunks: List<ByteArray>, maxFrame: Int = Frames.MAX_FRAME): Pair<List<ByteArray>, List<ProtocolError>> {
        val out = mutableListOf<ByteArray>()
        val errors = mutableListOf<ProtocolError>()
        val decoder = SlipDecoder(maxFrame)
        chunks.forEach { decoder.feed(it, onError = { e -> errors += e }) { f -> out += f } }
        return out to errors
    }

    private fun assertFrames(expected: List<ByteArray>, actual: List<ByteArray>) {
        assertEquals(expected.size, actual.size, "number of frames")
        expected.zip(actual).forEach { (e, a) -> assertContentEquals(e, a) }
    }

    @Test
    fun framesMergedInOneChunkAreSplit() {
        val (out, errors) = decodeChunks(listOf(stream))
        assertFrames(frames, out)
        assertTrue(errors.isEmpty())
    }

    @Test
    fun framesSplitAtEveryByteAreJoined() {
        val (out, errors) = decodeChunks(stream.map { byteArrayOf(it) })
        assertFrames(frames, out)
        assertTrue(errors.isEmpty())
    }

    @Test
    fun framesSplitInsideAnEscapeAreJoined() {
        val escAt = stream.indexOf(Slip.ESC)
        val (out, _) = decodeChunks(listOf(stream.copyOfRange(0, escAt + 1), stream.copyOfRange(escAt + 1, stream.size)))
        assertFrames(frames, out)
    }

    @Test
    fun emptyFramesAndEmptyChunksAreSkipped() {
        val (out, errors) = decodeChunks(listOf(ByteArray(0), byteArrayOf(Slip.END, Slip.END, Slip.END), ByteArray(0)))
        assertTrue(out.isEmpty())
        assertTrue(errors.isEmpty())
    }

    @Test
    fun oversizedFrameIsDroppedAndTheNextOneSurvives() {
        val big = ByteArray(Frames.MAX_FRAME + 10) { 0x11 }
        val (out, errors) = decodeChunks(listOf(Slip.encode(big), Slip.encode(frames[0])))
        assertFrames(listOf(frames[0]), out)
        assertEquals(listOf<ProtocolError>(ProtocolError.TooLong(Frames.MAX_FRAME + 10)), errors)
    }

    @Test
    fun invalidEscapeDropsOnlyThatFrame() {
        val bad = byteArrayOf(Slip.END, 1, 2, Slip.ESC, 0x55, 3, Slip.END)
        val (out, errors) = decodeChunks(listOf(bad, Slip.encode(frames[2])))
        assertFrames(listOf(frames[2]), out)
        assertEquals(ErrorCode.FRAMING, errors.single().code)
    }

    @Test
    fun aStreamJoinedInsideAFrameStartsAtTheNextFrameWithoutAnError() {
        // The tail of a frame sent before the receiver joined: escapes, an END inside it, whatever it holds.
        val earlier = Slip.encode(frames[1])
        val (out, errors) = decodeChunks(listOf(earlier.copyOfRange(earlier.size - 6, earlier.size), stream))
        assertFrames(frames, out)
        assertTrue(errors.isEmpty(), "$errors")
    }

    @Test
    fun garbageBetweenFramesBecomesAFrameThatFailsItsCrc() {
        val (out, _) = decodeChunks(listOf(Slip.encode(frames[0]), byteArrayOf(1, 2, 3, 4, 5, 6), stream))
        assertEquals(frames.size + 2, out.size)
        assertTrue(Frames.decode(out[1]) is FrameResult.Failed)
        assertFrames(listOf(frames[0]) + frames, out.take(1) + out.drop(2))
    }
}

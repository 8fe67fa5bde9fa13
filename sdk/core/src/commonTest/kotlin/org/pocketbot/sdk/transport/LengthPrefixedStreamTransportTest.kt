package org.pocketbot.sdk.transport

import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertIs
import kotlinx.coroutines.ExperimentalCoroutinesApi
import kotlinx.coroutines.test.StandardTestDispatcher
import kotlinx.coroutines.test.TestScope
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolError
import org.pocketbot.protocol.Slip

@OptIn(ExperimentalCoroutinesApi::class)
class LengthPrefixedStreamTransportTest {
    /** A frame holding SLIP's special bytes, which this framing carries as they are. */
    private val frame = byteArrayOf(0x42, 0x01, 4, Slip.END, Slip.ESC, Slip.END, 0x00, 0x11, 0x22)

    private fun TestScope.transport(pipe: MemoryPipe, maxFrame: Int = Frames.MAX_FRAME) =
        LengthPrefixedStreamTransport("pipe:test", pipe.hostStream, StandardTestDispatcher(testScheduler), maxFrame)

    private fun prefixed(f: ByteArray) = byteArrayOf(f.size.toByte(), (f.size shr 8).toByte()) + f

    @Test
    fun framesCutAnywhereArriveWholeAndInOrder() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        val frames = (1..4).map { Frames.encode(HelloRequest(it, 9L), seq = it) } + listOf(frame)
        val wire = frames.map(::prefixed).reduce { a, b -> a + b }
        // single bytes first (the length split in two), then the rest in one chunk
        pipe.robotSends(*wire.copyOfRange(0, 20).map { byteArrayOf(it) }.toTypedArray(), wire.copyOfRange(20, wire.size))
        for (expected in frames) assertContentEquals(expected, t.incoming.receive())
        assertEquals(0L, t.droppedFrames.value.total)
        t.close()
    }

    @Test
    fun sendPutsTheLengthLittleEndianBeforeTheFrameAndNoSlip() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        t.send(frame)
        assertContentEquals(byteArrayOf(frame.size.toByte(), 0) + frame, pipe.hostBytes())
        t.close()
    }

    @Test
    fun aFrameLongerThanTheLimitIsSkippedWholeAndCounted() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe, maxFrame = 8)
        pipe.robotSends(prefixed(frame) + prefixed(frame.copyOf(8)))
        assertContentEquals(frame.copyOf(8), t.incoming.receive())
        assertEquals(1L, t.droppedFrames.value.tooLong)
        assertIs<ProtocolError.TooLong>(t.lastFramingError.value)
        t.close()
    }

    @Test
    fun theOtherEndClosingLosesTheLink() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        pipe.robotSends(prefixed(frame).copyOf(5))
        pipe.robotHangsUp()
        assertFailsWith<TransportLostException> { t.incoming.receive() }
        assertFailsWith<TransportLostException> { t.send(frame) }
    }
}

package org.pocketbot.sdk.transport

import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertFalse
import kotlin.test.assertIs
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlinx.coroutines.ExperimentalCoroutinesApi
import kotlinx.coroutines.async
import kotlinx.coroutines.awaitAll
import kotlinx.coroutines.channels.ClosedReceiveChannelException
import kotlinx.coroutines.test.StandardTestDispatcher
import kotlinx.coroutines.test.TestScope
import kotlinx.coroutines.test.advanceUntilIdle
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder

@OptIn(ExperimentalCoroutinesApi::class)
class SlipStreamTransportTest {
    private val hello = Hello(3, "PocketBot-3", 0, 1, 0, ProtocolInfo.VERSION, ProtocolInfo.LAYOUT_HASH,
        ProtocolInfo.SETTINGS_SIZE, ProtocolInfo.STATE_SIZE, 0, 0x1234)
    private val helloFrame = Frames.encode(hello, seq = 7)

    /** A frame whose payload holds both SLIP special bytes, so escaping is exercised. */
    private val trickyFrame = byteArrayOf(0x42, 0x01, 4, Slip.END, Slip.ESC, Slip.END, 0x00, 0x11, 0x22)

    private fun TestScope.transport(pipe: MemoryPipe, maxFrame: Int = Frames.MAX_FRAME, capacity: Int = 256) =
        SlipStreamTransport("pipe:test", pipe.hostStream, StandardTestDispatcher(testScheduler), maxFrame, capacity)

    @Test
    fun aFrameCutIntoSingleBytesArrivesWhole() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        pipe.robotSends(*Slip.encode(helloFrame).map { byteArrayOf(it) }.toTypedArray())
        val frame = t.incoming.receive()
        assertContentEquals(helloFrame, frame)
        assertEquals(FrameResult.Decoded(7, hello), Frames.decode(frame))
        t.close()
    }

    @Test
    fun framesMergedIntoOneChunkArriveInOrder() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        val frames = (0 until 5).map { Frames.encode(HelloRequest(it, 1L), seq = it) } + listOf(trickyFrame)
        pipe.robotSends(frames.map { Slip.encode(it) }.reduce { a, b -> a + b })
        for (expected in frames) assertContentEquals(expected, t.incoming.receive())
        assertEquals(0L, t.droppedFrames.value.total)
        t.close()
    }

    @Test
    fun chunkBoundariesInsideEscapesDoNotMatter() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        val wire = Slip.encode(trickyFrame) + Slip.encode(helloFrame)
        // cut right after each ESC byte, so every escape straddles two reads
        val chunks = mutableListOf<ByteArray>()
        var start = 0
        for (i in wire.indices) if (wire[i] == Slip.ESC) { chunks += wire.copyOfRange(start, i + 1); start = i + 1 }
        chunks += wire.copyOfRange(start, wire.size)
        assertTrue(chunks.size > 2, "the frame should contain escapes")
        pipe.robotSends(*chunks.toTypedArray())
        assertContentEquals(trickyFrame, t.incoming.receive())
        assertContentEquals(helloFrame, t.incoming.receive())
        t.close()
    }

    @Test
    fun brokenFramingBetweenFramesIsCountedAndDropped() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        val badEscape = byteArrayOf(Slip.END, 0x10, Slip.ESC, 0x01, 0x20, Slip.END)
        val escapeAtEnd = byteArrayOf(0x33, Slip.ESC, Slip.END)
        pipe.robotSends(Slip.encode(helloFrame), badEscape, Slip.encode(trickyFrame), escapeAtEnd, Slip.encode(helloFrame))
        assertContentEquals(helloFrame, t.incoming.receive())
        assertContentEquals(trickyFrame, t.incoming.receive())
        assertContentEquals(helloFrame, t.incoming.receive())
        assertEquals(DroppedFrames(badFraming = 2), t.droppedFrames.value)
        assertTrue(t.lastFramingError.value!!.message.contains("escape"), "${t.lastFramingError.value}")
        t.close()
    }

    @Test
    fun lineNoiseBetweenFramesArrivesAsAFrameThatFailsItsCrc() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        val noise = byteArrayOf(0x55, 0x13, 0x7F, 0x00, 0x01, 0x02, 0x03)
        pipe.robotSends(Slip.encode(helloFrame), noise, Slip.encode(helloFrame))
        assertContentEquals(helloFrame, t.incoming.receive())
        // SLIP cannot tell noise from a frame; the frame layer rejects it, the stream survives
        val junk = t.incoming.receive()
        assertContentEquals(noise, junk)
        assertIs<FrameResult.Failed>(Frames.decode(junk))
        assertContentEquals(helloFrame, t.incoming.receive())
        assertEquals(0L, t.droppedFrames.value.total)
        t.close()
    }

    @Test
    fun aFrameLongerThanTheLimitIsDroppedAndTheNextOneArrives() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe, maxFrame = 16)
        val small = Frames.encode(HelloRequest(1, 1L), seq = 1)
        pipe.robotSends(Slip.encode(ByteArray(40) { it.toByte() }), Slip.encode(small))
        val frame = t.incoming.receive()
        assertContentEquals(small, frame)
        assertEquals(DroppedFrames(tooLong = 1), t.droppedFrames.value)
        t.close()
    }

    @Test
    fun sendWritesOneSlipEncodedFrame() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        t.send(trickyFrame)
        val wire = pipe.hostBytes()
        assertContentEquals(Slip.encode(trickyFrame), wire)
        val decoded = mutableListOf<ByteArray>()
        SlipDecoder().feed(wire) { decoded += it }
        assertEquals(1, decoded.size)
        assertContentEquals(trickyFrame, decoded[0])
        t.close()
    }

    @Test
    fun concurrentSendsDoNotInterleave() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        val frames = (0 until 50).map { Frames.encode(HelloRequest(it, 1L), seq = it) }
        frames.map { f -> async { t.send(f) } }.awaitAll()
        val received = mutableListOf<ByteArray>()
        SlipDecoder().feed(pipe.hostBytes()) { received += it }
        assertEquals(frames.size, received.size)
        assertEquals(frames.map { it.toList() }.toSet(), received.map { it.toList() }.toSet())
        t.close()
    }

    @Test
    fun endOfStreamLosesTheLink() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        pipe.robotSends(Slip.encode(helloFrame))
        pipe.robotHangsUp()
        assertContentEquals(helloFrame, t.incoming.receive(), "frames received before the loss are kept")
        val e = assertFailsWith<TransportLostException> { t.incoming.receive() }
        assertTrue(e.message!!.startsWith("pipe:test"), e.message)
        assertFalse(t.isOpen)
        assertFailsWith<TransportLostException> { t.send(helloFrame) }
        assertEquals(1, pipe.closeCount, "the stream is closed once")
        t.close()
        assertEquals(1, pipe.closeCount)
    }

    @Test
    fun aFailingReadLosesTheLinkWithTheCause() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        val cause = FakeIoException("cable cut")
        pipe.linkBreaks(cause)
        val e = assertFailsWith<TransportLostException> { t.incoming.receive() }
        assertTrue(e.message!!.contains("cable cut"), e.message)
        // the channel may hand out a copy of the exception (coroutines' stack trace recovery): look along the chain
        assertTrue(generateSequence<Throwable>(e) { it.cause }.any { it is FakeIoException }, "cause lost: $e")
        assertFailsWith<TransportLostException> { t.send(helloFrame) }
    }

    @Test
    fun aFailingWriteLosesTheLink() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        pipe.writeFailure = FakeIoException("broken pipe")
        val e = assertFailsWith<TransportLostException> { t.send(helloFrame) }
        assertTrue(e.message!!.contains("broken pipe"), e.message)
        assertFailsWith<TransportLostException> { t.incoming.receive() }
        assertFalse(t.isOpen)
        assertEquals(1, pipe.closeCount)
    }

    @Test
    fun closeIsIdempotentAndEndsIncomingNormally() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe)
        pipe.robotSends(Slip.encode(helloFrame))
        advanceUntilIdle()
        t.close()
        t.close()
        assertEquals(1, pipe.closeCount)
        assertFalse(t.isOpen)
        assertContentEquals(helloFrame, t.incoming.receive(), "frames received before close are kept")
        val end = t.incoming.receiveCatching()
        assertTrue(end.isClosed)
        assertNull(end.exceptionOrNull(), "closing is not a lost link")
        assertFailsWith<ClosedReceiveChannelException> { t.incoming.receive() }
        val e = assertFailsWith<TransportLostException> { t.send(helloFrame) }
        assertTrue(e.message!!.contains("closed"), e.message)
    }

    @Test
    fun closeWhileTheReaderWaitsForAFullIncomingEndsCleanly() = runTest {
        val pipe = MemoryPipe()
        val t = transport(pipe, capacity = 1)
        pipe.robotSends(Slip.encode(helloFrame) + Slip.encode(helloFrame) + Slip.encode(helloFrame))
        advanceUntilIdle()
        t.close()
        advanceUntilIdle()
        assertContentEquals(helloFrame, t.incoming.receive())
        assertNull(t.incoming.receiveCatching().exceptionOrNull())
    }
}

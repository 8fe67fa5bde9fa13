package org.pocketbot.sdk.transport

import java.io.File
import java.io.FileInputStream
import java.io.FileOutputStream
import kotlin.test.AfterTest
import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.channels.ClosedReceiveChannelException
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import kotlinx.coroutines.flow.toList
import org.junit.jupiter.api.Assumptions.assumeTrue
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.Slip

/** [SerialTransport] through jSerialComm on real pseudo-terminals made by socat, a fake robot on the other end. */
class SerialTransportTest {
    private val toClose = mutableListOf<AutoCloseable>()

    @AfterTest
    fun cleanUp() = toClose.reversed().forEach { runCatching { it.close() } }

    private fun test(block: suspend CoroutineScope.() -> Unit): Unit =
        runBlocking(Dispatchers.IO) { withTimeout(30.seconds) { block() } }

    private class Link(val socat: Socat, val hostPath: File, val robot: FakeRobot)

    private fun link(): Link {
        assumeTrue(Socat.available, "socat is not installed")
        val socat = Socat.ptyPair().also { toClose += it }
        val (host, robotSide) = socat.links
        val robot = FakeRobot(FileInputStream(robotSide), FileOutputStream(robotSide)).also { toClose += it }
        return Link(socat, host, robot)
    }

    @Test
    fun theSerialDiscovererFindsTheRobotBehindAPortAndSkipsSilentAndMissingOnes() = test {
        val robot = link()
        assumeTrue(Socat.available, "socat is not installed")
        val silent = Socat.ptyPair().also { toClose += it } // nothing answers on the other end
        val ports = listOf(robot.hostPath.path, silent.links[0].path, "/dev/pocketbot-no-such-port")
        val found = SerialDiscoverer(ports = { ports }).discover().toList()
        assertEquals(listOf(robot.hostPath.path), found.map { (it as SerialRobotDevice).path })
        assertEquals(robot.robot.hello.name, found.single().name)
        assertEquals("serial:${robot.hostPath.path}", found.single().address)
    }

    @Test
    fun aMergedSearchGoesOnWhenOneSourceFails() = test {
        val robot = link()
        val failures = mutableListOf<String>()
        val merged = MergedDiscoverer(
            mapOf(
                "serial" to SerialDiscoverer(ports = { listOf(robot.hostPath.path) }),
                "emulator" to EmulatorDiscoverer(controlPort = java.net.ServerSocket(0).use { it.localPort }),
            ),
        ) { source, e -> synchronized(failures) { failures += "$source: ${e.message}" } }
        val found = merged.discover().toList()
        assertEquals(1, found.size)
        assertTrue(failures.single().startsWith("emulator: no emulator control port"), "$failures")
    }

    @Test
    fun aHelloRequestIsAnsweredThroughAPty() = test {
        val link = link()
        val t = SerialRobotDevice(link.hostPath.path).open()
        assertEquals("serial:${link.hostPath.path}", t.address)
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 1L), seq = 5))
        assertEquals(FrameResult.Decoded(5, link.robot.hello), Frames.decode(t.incoming.receive()))
        t.close()
    }

    @Test
    fun theRealPtyPathWorksToo() = test {
        val link = link()
        val t = SerialTransport.open(link.socat.realPath(link.hostPath))
        assertTrue(t.address.startsWith("serial:/dev/pts/"), t.address)
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 1L), seq = 6))
        assertEquals(FrameResult.Decoded(6, link.robot.hello), Frames.decode(t.incoming.receive()))
        t.close()
    }

    @Test
    fun everyByteValueCrossesInBothDirections() = test {
        val link = link()
        val t = SerialTransport.open(link.hostPath.path)
        // all 256 values, in frames of up to 64 bytes: the tty must be raw (no CR/LF mapping, no XON/XOFF)
        val frames = (0 until 256 step 64).map { start -> ByteArray(64) { (start + it).toByte() } }
        for (f in frames) t.send(f)
        for (f in frames) assertContentEquals(f, link.robot.nextFrame())
        link.robot.sendRaw(frames.map { Slip.encode(it) }.reduce { a, b -> a + b })
        for (f in frames) assertContentEquals(f, t.incoming.receive())
        assertEquals(0L, t.droppedFrames.value.total)
        t.close()
    }

    @Test
    fun thePtyGoingAwayLosesTheLink() = test {
        val link = link()
        val t = SerialTransport.open(link.hostPath.path)
        link.socat.close()
        val e = assertFailsWith<TransportLostException> { t.incoming.receive() }
        assertTrue(e.message!!.contains("serial:"), e.message)
        assertFailsWith<TransportLostException> { t.send(byteArrayOf(1, 2, 3, 4, 5)) }
        t.close()
    }

    @Test
    fun closeIsIdempotent() = test {
        val link = link()
        val t = SerialTransport.open(link.hostPath.path)
        t.close()
        t.close()
        assertFailsWith<ClosedReceiveChannelException> { t.incoming.receive() }
        assertFailsWith<TransportLostException> { t.send(byteArrayOf(1, 2, 3, 4, 5)) }
        // the port is free again
        val again = SerialTransport.open(link.hostPath.path)
        again.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 1L), seq = 1))
        assertEquals(FrameResult.Decoded(1, link.robot.hello), Frames.decode(again.incoming.receive()))
        again.close()
    }

    @Test
    fun aMissingPortFailsWithTransportLost() = test {
        val e = assertFailsWith<TransportLostException> { SerialRobotDevice("/dev/does-not-exist-pocketbot").open() }
        assertTrue(e.message!!.startsWith("serial:/dev/does-not-exist-pocketbot"), e.message)
    }
}

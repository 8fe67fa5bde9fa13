package org.pocketbot.sdk.transport

import java.net.InetAddress
import java.net.InetSocketAddress
import java.net.ServerSocket
import kotlin.test.AfterTest
import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.async
import kotlinx.coroutines.awaitAll
import kotlinx.coroutines.channels.ClosedReceiveChannelException
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.Slip

class TcpTransportTest {
    private val server = ServerSocket().apply { bind(InetSocketAddress(InetAddress.getLoopbackAddress(), 0)) }
    private val port = server.localPort
    private val toClose = mutableListOf<AutoCloseable>()

    /** Accepts the next connection on [server] and puts a fake robot on it. */
    private fun acceptRobot(): FakeRobot {
        server.soTimeout = 5000
        val socket = server.accept()
        socket.tcpNoDelay = true
        return FakeRobot(socket.getInputStream(), socket.getOutputStream(), onEnd = { socket.close() })
            .also { toClose += it }
    }

    @AfterTest
    fun cleanUp() {
        toClose.forEach { runCatching { it.close() } }
        server.close()
    }

    /** Runs on IO threads: the fake robot's accept blocks while the transport connects in another coroutine. */
    private fun test(block: suspend CoroutineScope.() -> Unit): Unit =
        runBlocking(Dispatchers.IO) { withTimeout(20.seconds) { block() } }

    @Test
    fun aHelloRequestIsAnsweredWithTheRobotsHello() = test {
        val device = TcpRobotDevice("127.0.0.1", port)
        val opening = async { device.open() }
        val robot = acceptRobot()
        val t = opening.await()
        assertEquals("tcp://127.0.0.1:$port", t.address)
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION), seq = 42))
        val reply = Frames.decode(t.incoming.receive())
        assertEquals(FrameResult.Decoded(42, robot.hello), reply)
        t.close()
    }

    @Test
    fun framesFlowBothWaysInOrder() = test {
        val opening = async { TcpTransport.connect("127.0.0.1", port) }
        val robot = acceptRobot()
        val t = opening.await()
        // not hello requests (the fake robot answers those): any bytes, including SLIP's special ones
        val toRobot = (0 until 300).map { i -> byteArrayOf(0x20, i.toByte(), (i shr 8).toByte(), Slip.ESC, Slip.END, 1, 2) }
        toRobot.map { async { t.send(it) } }.awaitAll()
        val got = (toRobot.indices).map { robot.nextFrame() }
        assertEquals(toRobot.map { it.toList() }.toSet(), got.map { it.toList() }.toSet())

        val toHost = (0 until 300).map { i -> byteArrayOf(0x10, i.toByte(), 3, Slip.END, Slip.ESC, i.toByte(), 0, 0) }
        robot.sendRaw(toHost.map { Slip.encode(it) }.reduce { a, b -> a + b })
        for (expected in toHost) assertContentEquals(expected, t.incoming.receive())
        t.close()
    }

    @Test
    fun brokenFramingFromTheRobotIsCountedAndTheLinkGoesOn() = test {
        val opening = async { TcpTransport.connect("127.0.0.1", port) }
        val robot = acceptRobot()
        val t = opening.await()
        robot.sendRaw(byteArrayOf(Slip.END, 1, 2, Slip.ESC, 7, 3, Slip.END))
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION), seq = 1))
        assertTrue(Frames.decode(t.incoming.receive()) is FrameResult.Decoded)
        assertEquals(1L, t.framingErrors.value)
        t.close()
    }

    @Test
    fun theRobotHangingUpLosesTheLink() = test {
        val opening = async { TcpTransport.connect("127.0.0.1", port) }
        val robot = acceptRobot()
        val t = opening.await()
        robot.sendFrame(Frames.encode(HelloRequest(1), seq = 1))
        robot.close()
        assertContentEquals(Frames.encode(HelloRequest(1), seq = 1), t.incoming.receive())
        val e = assertFailsWith<TransportLostException> { t.incoming.receive() }
        assertTrue(e.message!!.startsWith("tcp://127.0.0.1:$port"), e.message)
        assertFailsWith<TransportLostException> { t.send(Frames.encode(HelloRequest(1), seq = 2)) }
        t.close()
    }

    @Test
    fun closeIsIdempotentAndTheRobotSeesTheEnd() = test {
        val opening = async { TcpTransport.connect("127.0.0.1", port) }
        val robot = acceptRobot()
        val t = opening.await()
        t.close()
        t.close()
        robot.awaitEnd()
        assertFailsWith<ClosedReceiveChannelException> { t.incoming.receive() }
        assertFailsWith<TransportLostException> { t.send(byteArrayOf(1, 2, 3, 4, 5)) }
    }

    @Test
    fun connectingWhereNothingListensFailsWithTransportLost() = test {
        val closedPort = ServerSocket(0, 1, InetAddress.getLoopbackAddress()).use { it.localPort }
        val e = assertFailsWith<TransportLostException> { TcpRobotDevice("127.0.0.1", closedPort).open() }
        assertTrue(e.message!!.contains("cannot connect"), e.message)
    }

    @Test
    fun theEmulatorDiscovererListsTheRobotsOfTheControlPort() = test {
        val listing = async {
            EmulatorDiscoverer("127.0.0.1", port).list()
        }
        server.soTimeout = 5000
        server.accept().use { s ->
            s.getOutputStream().write("1\tPocketBot-1\t40001\n2\tPocketBot 2\t40002\nnot a robot\n7\tx\t99999\n".toByteArray())
        }
        val devices = listing.await()
        assertEquals(listOf("PocketBot-1" to 40001, "PocketBot 2" to 40002), devices.map { it.name to it.port })
        assertEquals("tcp://127.0.0.1:40001", devices[0].address)
    }

    @Test
    fun theEmulatorDiscovererFailsClearlyWhenNoEmulatorRuns() = test {
        val closedPort = ServerSocket(0, 1, InetAddress.getLoopbackAddress()).use { it.localPort }
        val e = assertFailsWith<TransportLostException> { EmulatorDiscoverer(controlPort = closedPort).list() }
        assertTrue(e.message!!.contains("no emulator control port"), e.message)
    }

    @Test
    fun aRobotBehindADiscoveredDeviceAnswers() = test {
        val controlPort = ServerSocket(0, 1, InetAddress.getLoopbackAddress())
        toClose += controlPort
        val listing = async { EmulatorDiscoverer(controlPort = controlPort.localPort).list() }
        controlPort.accept().use { it.getOutputStream().write("3\tPocketBot-3\t$port\n".toByteArray()) }
        val device = listing.await().single()
        val opening = async { device.open() }
        val robot = acceptRobot()
        val t = opening.await()
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION), seq = 9))
        assertEquals(FrameResult.Decoded(9, robot.hello), Frames.decode(t.incoming.receive()))
        t.close()
    }
}

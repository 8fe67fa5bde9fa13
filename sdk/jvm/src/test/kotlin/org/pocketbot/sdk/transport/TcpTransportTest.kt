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
import kotlinx.coroutines.launch
import kotlinx.coroutines.awaitAll
import kotlinx.coroutines.channels.ClosedReceiveChannelException
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import kotlinx.coroutines.flow.first
import org.pocketbot.sdk.ConnectFailedException
import org.pocketbot.sdk.connect
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.Slip
import org.pocketbot.sdk.connect

class TcpTransportTest {
    private val server = ServerSocket().apply { bind(InetSocketAddress(InetAddress.getLoopbackAddress(), 0)) }
    private val port = server.localPort
    private val toClose = mutableListOf<AutoCloseable>()

    /** Accepts the next connection on [server] and puts a fake robot on it. */
    private fun acceptRobot(answersCommands: Boolean = false): FakeRobot {
        server.soTimeout = 5000
        val socket = server.accept()
        socket.tcpNoDelay = true
        return FakeRobot(socket.getInputStream(), socket.getOutputStream(), onEnd = { socket.close() }, answersCommands = answersCommands)
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
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 1L), seq = 42))
        val reply = Frames.decode(t.incoming.receive())
        assertEquals(FrameResult.Decoded(42, robot.hello), reply)
        t.close()
    }

    @Test
    fun framesFlowBothWaysInOrder() = test {
        val opening = async { TcpTransport.open("127.0.0.1", port) }
        val robot = acceptRobot()
        val t = opening.await()
        // not hello requests (the fake robot answers those): any bytes, including SLIP's special ones
        val toRobot = (0 until 300).map { i -> byteArrayOf(0x20, i.toByte(), (i shr 8).toByte(), Slip.ESC, Slip.END, 1, 2) }
        for (f in toRobot) t.send(f)
        val got = (toRobot.indices).map { robot.nextFrame() }
        assertEquals(toRobot.map { it.toList() }, got.map { it.toList() }, "frames sent one after the other arrive in that order")

        val toHost = (0 until 300).map { i -> byteArrayOf(0x10, i.toByte(), 3, Slip.END, Slip.ESC, i.toByte(), 0, 0) }
        robot.sendRaw(toHost.map { Slip.encode(it) }.reduce { a, b -> a + b })
        for (expected in toHost) assertContentEquals(expected, t.incoming.receive())
        t.close()
    }

    @Test
    fun concurrentSendersNeverInterleaveTheirFrames() = test {
        val opening = async { TcpTransport.open("127.0.0.1", port) }
        val robot = acceptRobot()
        val t = opening.await()
        val toRobot = (0 until 300).map { i -> byteArrayOf(0x20, i.toByte(), (i shr 8).toByte(), Slip.ESC, Slip.END, 1, 2) }
        toRobot.map { async { t.send(it) } }.awaitAll()
        // Coroutines sending at once have no order among them, but every frame arrives whole.
        val got = (toRobot.indices).map { robot.nextFrame() }
        assertEquals(toRobot.map { it.toList() }.sortedBy { it.toString() }, got.map { it.toList() }.sortedBy { it.toString() })
        t.close()
    }

    @Test
    fun anOversizedFrameFromTheRobotIsCountedInTheRobotsLinkStats() = test {
        val device = TcpRobotDevice("127.0.0.1", port)
        val scope = this // the robot belongs to the test, not to the async that connects it
        val connecting = async { device.connect(scope, org.pocketbot.sdk.RobotOptions { syncMode = org.pocketbot.sdk.SyncMode.NONE; settingsCache = null }) }
        val robot = acceptRobot(answersCommands = true)
        val sdk = connecting.await()
        robot.sendRaw(Slip.encode(ByteArray(Frames.MAX_FRAME + 50) { 0x11 }))
        robot.sendRaw(byteArrayOf(Slip.END, 1, 2, Slip.ESC, 7, 3, Slip.END))
        kotlinx.coroutines.withTimeoutOrNull(5.seconds) { sdk.linkStats.first { it.tooLong == 1L && it.badFraming == 1L } } ?: error("not counted: ${sdk.linkStats.value} ${sdk.connection.value}")
        assertEquals(2L, sdk.linkStats.value.dropped)
        assertEquals(org.pocketbot.sdk.ConnectionState.Connected, sdk.connection.value, "the link survives broken frames")
        sdk.disconnect()
    }

    @Test
    fun aTcpRobotsStateReachesItsFlowOnTheSocketsOwnLoopThread() = test {
        val device = TcpRobotDevice("127.0.0.1", port)
        val scope = this
        val connecting = async { device.connect(scope, org.pocketbot.sdk.RobotOptions { syncMode = org.pocketbot.sdk.SyncMode.NONE; settingsCache = null }) }
        val robot = acceptRobot(answersCommands = true)
        val sdk = connecting.await()
        val threads = java.util.concurrent.ConcurrentLinkedQueue<String>()
        val watching = launch(Dispatchers.Unconfined) { sdk.stateUpdates.collect { threads += Thread.currentThread().name } }
        repeat(5) { robot.sendFrame(Frames.encode(org.pocketbot.protocol.StateFull(org.pocketbot.protocol.RobotState.decode(ByteArray(ProtocolInfo.STATE_SIZE), 0)), 0)) }
        kotlinx.coroutines.withTimeoutOrNull(5.seconds) { while (threads.size < 5) kotlinx.coroutines.delay(10) }
        watching.cancel()
        assertEquals(5, threads.size, "every state arrived")
        assertTrue(threads.all { it.startsWith("pocketbot-sockets") }, "read, decoded and emitted on the socket's loop, no hand-over: $threads")
        sdk.disconnect()
    }

    @Test
    fun brokenFramingFromTheRobotIsCountedAndTheLinkGoesOn() = test {
        val opening = async { TcpTransport.open("127.0.0.1", port) }
        val robot = acceptRobot()
        val t = opening.await()
        robot.sendRaw(byteArrayOf(Slip.END, 1, 2, Slip.ESC, 7, 3, Slip.END))
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 1L), seq = 1))
        assertTrue(Frames.decode(t.incoming.receive()) is FrameResult.Decoded)
        assertEquals(1L, t.droppedFrames.value.total)
        t.close()
    }

    @Test
    fun theRobotHangingUpLosesTheLink() = test {
        val opening = async { TcpTransport.open("127.0.0.1", port) }
        val robot = acceptRobot()
        val t = opening.await()
        robot.sendFrame(Frames.encode(HelloRequest(1, 1L), seq = 1))
        robot.close()
        assertContentEquals(Frames.encode(HelloRequest(1, 1L), seq = 1), t.incoming.receive())
        val e = assertFailsWith<TransportLostException> { t.incoming.receive() }
        assertTrue(e.message!!.startsWith("tcp://127.0.0.1:$port"), e.message)
        assertFailsWith<TransportLostException> { t.send(Frames.encode(HelloRequest(1, 1L), seq = 2)) }
        t.close()
    }

    @Test
    fun closeIsIdempotentAndTheRobotSeesTheEnd() = test {
        val opening = async { TcpTransport.open("127.0.0.1", port) }
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
        assertEquals("tcp://127.0.0.1:$closedPort: nothing listens there (connection refused): is the emulator " +
            "(make emulator, pocketbot emulator) or the robot's TCP bridge running?", e.message)
    }

    @Test
    fun connectingARobotWhereNothingListensSaysSoWithTheAddressOnce() = test {
        val closedPort = ServerSocket(0, 1, InetAddress.getLoopbackAddress()).use { it.localPort }
        val started = System.nanoTime()
        val e = assertFailsWith<ConnectFailedException> { TcpRobotDevice("127.0.0.1", closedPort).connect(this) }
        assertEquals("cannot connect to tcp://127.0.0.1:$closedPort: nothing listens there (connection refused): is the " +
            "emulator (make emulator, pocketbot emulator) or the robot's TCP bridge running?", e.message)
        assertTrue(System.nanoTime() - started < 2_000_000_000L, "at once, not after the handshake's retries")
    }

    @Test
    fun theEmulatorDiscovererListsTheRobotsOfTheControlPort() = test {
        val listing = async {
            EmulatorDiscoverer("127.0.0.1", port).list()
        }
        server.soTimeout = 5000
        server.accept().use { s ->
            // Lines name the host the client reached (a fourth field, which emulators before it left out).
            s.getOutputStream().write("1\tPocketBot-1\t40001\t127.0.0.1\n2\tPocketBot 2\t40002\nnot a robot\n7\tx\t99999\t127.0.0.1\n".toByteArray())
        }
        val devices = listing.await()
        assertEquals(listOf("PocketBot-1" to 40001, "PocketBot 2" to 40002), devices.map { it.name to it.port })
        assertEquals("tcp://127.0.0.1:40001", devices[0].address)
    }

    @Test
    fun theEmulatorDiscovererReachesTheRobotsWhereItReachedTheControlPort() = test {
        // Behind port forwarding (an Android emulator's 10.0.2.2, adb reverse) the emulator sees another address than
        // the one the client used: the client's own host is the one that works.
        val listing = async { EmulatorDiscoverer("127.0.0.1", port).list() }
        server.soTimeout = 5000
        server.accept().use { s -> s.getOutputStream().write("1\tPocketBot-1\t40001\t10.0.2.15\n".toByteArray()) }
        assertEquals(listOf("tcp://127.0.0.1:40001"), listing.await().map { it.address })
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
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 1L), seq = 9))
        assertEquals(FrameResult.Decoded(9, robot.hello), Frames.decode(t.incoming.receive()))
        t.close()
    }
}

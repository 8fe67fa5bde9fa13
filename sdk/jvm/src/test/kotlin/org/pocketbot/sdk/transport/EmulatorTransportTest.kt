package org.pocketbot.sdk.transport

import kotlin.test.AfterTest
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.fail
import kotlin.time.Duration.Companion.seconds
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import kotlinx.coroutines.withTimeoutOrNull
import org.junit.jupiter.api.Assumptions.assumeTrue
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.Pose
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.connect
import java.net.ConnectException
import java.net.Inet4Address
import java.net.InetAddress
import java.net.NetworkInterface
import java.net.Socket
import kotlin.math.hypot
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.StateFull

/**
 * The JVM transports against the emulator, i.e. against the real firmware: robots found through the control
 * port, reached over TCP, and over a serial pty that socat bridges to a robot's TCP endpoint.
 */
class EmulatorTransportTest {
    private val toClose = mutableListOf<AutoCloseable>()

    @AfterTest
    fun cleanUp() = toClose.reversed().forEach { runCatching { it.close() } }

    private fun test(block: suspend CoroutineScope.() -> Unit): Unit =
        runBlocking(Dispatchers.IO) { withTimeout(60.seconds) { block() } }

    /** An emulator of [robots] robots running in real time, with TCP endpoints on [listen]; returns its control port. */
    private fun emulator(robots: Int, listen: InetAddress = ListenAddress.LOOPBACK): Pair<Emulator, Int> {
        val emu = Emulator.local(robots = robots).also { toClose += it }
        val controlPort = emu.startTcp(basePort = 0, controlPort = 0, listen = listen)
        emu.start(Speed.Realtime(1.0))
        return emu to controlPort
    }

    /**
     * Asks for the robot's hello and returns it, skipping whatever else the robot sends meanwhile (state
     * packets). The robot numbers its frames itself, so the answer's seq is the robot's, not the request's.
     */
    private suspend fun hello(t: Transport, seq: Int): Hello {
        val seen = mutableListOf<String>()
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 1L), seq))
        return withTimeoutOrNull(15.seconds) {
            while (true) {
                val r = Frames.decode(t.incoming.receive())
                if (r is FrameResult.Decoded && r.packet is Hello) return@withTimeoutOrNull r.packet as Hello
                if (seen.size < 10) seen += if (r is FrameResult.Decoded) r.packet::class.simpleName!! else r.toString()
            }
            @Suppress("UNREACHABLE_CODE") null
        } ?: fail("no hello from ${t.address} within 15 s; received first: $seen")
    }

    private fun assertCompatible(hello: Hello, id: Int) {
        assertEquals(id, hello.robotId, "robot id in $hello")
        assertEquals(ProtocolInfo.VERSION, hello.protocolVersion, "protocol version in $hello")
        assertEquals(ProtocolInfo.LAYOUT_HASH, hello.layoutHash, "layout hash in $hello")
    }

    @Test
    fun theControlPortListsEveryRobotAndEachAnswersOverTcp() = test {
        val (emu, controlPort) = emulator(robots = 3)
        val devices = EmulatorDiscoverer(controlPort = controlPort).discover().toList()
        assertEquals(emu.robots.map { it.name }, devices.map { it.name })
        assertEquals(emu.robots.map { "tcp://127.0.0.1:${it.tcpPort}" }, devices.map { it.address })
        for ((i, device) in devices.withIndex()) {
            val t = device.open()
            assertCompatible(hello(t, seq = 10 + i), emu.robots[i].id)
            assertEquals(0L, (t as TcpTransport).droppedFrames.value.total)
            t.close()
        }
    }

    @Test
    fun anEmulatorOnTheNetworkIsFoundAndDrivenFromAnotherMachinesPointOfView() = test {
        val network = NetworkInterface.getNetworkInterfaces().toList().filter { it.isUp && !it.isLoopback }
            .flatMap { it.inetAddresses.toList() }.firstOrNull { it is Inet4Address && !it.isLinkLocalAddress }
        assumeTrue(network != null, "this machine has no network address besides loopback: a phone's view of the emulator cannot be tried here")
        val host = network!!.hostAddress
        val (emu, controlPort) = emulator(robots = 2, listen = ListenAddress.ANY)
        // As a phone on the same Wi-Fi does: the control port at the computer's network address, the robots there too.
        val devices = EmulatorDiscoverer(host, controlPort).list()
        assertEquals(emu.robots.map { "tcp://$host:${it.tcpPort}" }, devices.map { it.address })
        val robot = devices[1].connect(this, RobotOptions { settingsCache = InMemorySettingsCache() })
        val sim = emu.robots[1]
        assertEquals(sim.name, robot.identity.name)
        assertEquals(host, sim.tcpClient?.address?.hostAddress, "the robot is held from the network address")

        sim.place(Pose.ofDegrees(0.5, 0.5, 30.0)) // open floor
        val start = sim.truePose
        val result = robot.locomotion.enqueue(Movement.Straight(0.05, speedMps = 0.1)).await()
        assertEquals(MovementOutcome.FINISHED, result.outcome, "$result")
        val moved = hypot(sim.truePose.xM - start.xM, sim.truePose.yM - start.yM)
        assertTrue(moved in 0.045..0.055, "driven 5 cm over the network: the robot really moved ${moved * 1000} mm")
        robot.disconnect()
    }

    @Test
    fun anEmulatorOnLoopbackIsNotReachableFromTheNetwork() = test {
        val network = NetworkInterface.getNetworkInterfaces().toList().filter { it.isUp && !it.isLoopback }
            .flatMap { it.inetAddresses.toList() }.firstOrNull { it is Inet4Address && !it.isLinkLocalAddress }
        assumeTrue(network != null, "this machine has no network address besides loopback: nothing to be refused from")
        val (emu, controlPort) = emulator(robots = 1)
        val e = assertFailsWith<TransportLostException> { EmulatorDiscoverer(network!!.hostAddress, controlPort).list() }
        assertTrue(e.message!!.contains("refused"), "refused, not timed out: $e")
        assertFailsWith<ConnectException> { Socket(network, emu.robots.single().tcpPort).close() }
    }

    @Test
    fun theFirmwareCountsACorruptedFrameTheHostSent() = test {
        val (_, controlPort) = emulator(robots = 1)
        val t = EmulatorDiscoverer(controlPort = controlPort).list().single().open()
        val frame = Frames.encode(HelloRequest(ProtocolInfo.VERSION, 1L), seq = 1)
        frame[frame.size - 1] = (frame[frame.size - 1].toInt() xor 0x5A).toByte()
        t.send(frame)
        // the robot's own state reports the CRC error: proof that the host's bytes reached the firmware intact
        // as a frame (SLIP decoded there), and that only the CRC was wrong
        val counted = withTimeoutOrNull(15.seconds) {
            while (true) {
                val r = Frames.decode(t.incoming.receive())
                if (r is FrameResult.Decoded && (r.packet as? StateFull)?.state?.errors?.crc == 1) return@withTimeoutOrNull true
            }
            @Suppress("UNREACHABLE_CODE") false
        }
        assertEquals(true, counted, "no state with errors.crc == 1 within 15 s")
        t.close()
    }

    @Test
    fun aRobotAnswersThroughASerialPtyBridgedToItsTcpEndpoint() = test {
        assumeTrue(Socat.available, "socat is not installed")
        val (emu, _) = emulator(robots = 1)
        val robot = emu.robots.single()
        val bridge = Socat.ptyToTcp(robot.tcpPort).also { toClose += it }
        val t = SerialRobotDevice(bridge.links.single().path).open()
        assertCompatible(hello(t, seq = 77), robot.id)
        t.close()
    }
}

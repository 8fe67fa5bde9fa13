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

    /** An emulator of [robots] robots running in real time, with TCP endpoints; returns its control port. */
    private fun emulator(robots: Int): Pair<Emulator, Int> {
        val emu = Emulator.local(robots = robots).also { toClose += it }
        val controlPort = emu.startTcp(basePort = 0, controlPort = 0)
        emu.start(Speed.Realtime(1.0))
        return emu to controlPort
    }

    /**
     * Asks for the robot's hello and returns it, skipping whatever else the robot sends meanwhile (state
     * packets). The robot numbers its frames itself, so the answer's seq is the robot's, not the request's.
     */
    private suspend fun hello(t: Transport, seq: Int): Hello {
        val seen = mutableListOf<String>()
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION), seq))
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
            assertEquals(0L, (t as TcpTransport).framingErrors.value)
            t.close()
        }
    }

    @Test
    fun theFirmwareCountsACorruptedFrameTheHostSent() = test {
        val (_, controlPort) = emulator(robots = 1)
        val t = EmulatorDiscoverer(controlPort = controlPort).list().single().open()
        val frame = Frames.encode(HelloRequest(ProtocolInfo.VERSION), seq = 1)
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

package org.pocketbot.emulator

import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.emulator.firmware.FirmwareImage
import org.pocketbot.emulator.link.LinkSettings
import org.pocketbot.sdk.Pose
import org.pocketbot.emulator.world.Worlds
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Heartbeat
import java.nio.ByteBuffer
import java.nio.ByteOrder
import kotlin.math.PI
import kotlin.math.abs
import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * The emulator's wiring, checked with a tiny stand-in firmware (src/test/c/standin.c, run by Chicory's
 * interpreter) so it does not depend on the real firmware: exports, the sensors' inputs, encoder edges, IR, the link.
 */
class StandInWiringTest {
    private val standIn = FirmwareImage.interpreted(
        StandInWiringTest::class.java.getResourceAsStream("/standin.wasm")!!.readBytes(), "standin.wasm",
    )

    private fun emulator(world: String = "straight", seed: Long = 1) =
        Emulator(Worlds.load(world), EmulatorConfig(seed = seed, firmware = standIn))

    /** The stand-in's state struct (see standin.c). */
    private class StandInState(bytes: ByteArray) {
        private val b = ByteBuffer.wrap(bytes).order(ByteOrder.LITTLE_ENDIAN)
        val now = b.getLong(0)
        val lastEdge = longArrayOf(b.getLong(8), b.getLong(16))
        val edges = intArrayOf(b.getInt(24), b.getInt(28))
        val irHeard = b.getInt(32)
        val irSender = b.getInt(36)
        val irSide = b.getInt(40)
        val irLed = b.getInt(44)
        val adc = IntArray(4) { b.getInt(52 + 4 * it) }
        val batteryMv = b.getInt(68)
        val id = b.getInt(72)
        val rxCount = b.getInt(76)
    }

    private fun RobotHandle.standInState() = StandInState(stateBytes())

    @Test
    fun `the firmware is booted with its id and sees time advance`() = emulator().use { emu ->
        val r = emu.addRobot(id = 7)
        emu.runFor(100.milliseconds)
        val s = r.standInState()
        assertEquals(7, s.id)
        assertEquals(100L * 32_000, s.now, "firmware time after 100 ms")
        assertTrue(s.batteryMv in 3600..4200, "battery ${s.batteryMv} mV")
    }

    @Test
    fun `encoder edges match the wheels' true travel and arrive in time order`() = emulator().use { emu ->
        val r = emu.addRobot()
        emu.runFor(1.seconds)
        val s = r.standInState()
        val d = r.trueWheelDistances
        val perEdge = PI * 0.009 / 40
        assertTrue(d.leftM > 0.2, "robot at PWM 500 drove ${d.leftM} m in 1 s")
        assertTrue(abs(s.edges[0] - d.leftM / perEdge) <= 1.01, "left edges ${s.edges[0]} vs ${d.leftM / perEdge}")
        assertTrue(abs(s.edges[1] - d.rightM / perEdge) <= 1.01, "right edges ${s.edges[1]} vs ${d.rightM / perEdge}")
        assertTrue(s.lastEdge[0] in (s.now - 32_000 * 5)..s.now, "last edge at ${s.lastEdge[0]}, now ${s.now}")
    }

    @Test
    fun `the motor reaches 63 percent of its final speed after one time constant`() = emulator().use { emu ->
        val r = emu.addRobot()
        emu.runFor(500.milliseconds)
        val d0 = r.trueWheelDistances.leftM
        emu.runFor(100.milliseconds)
        val vFinal = (r.trueWheelDistances.leftM - d0) / 0.1
        emu.close()
        emulator().use { emu2 ->
            val r2 = emu2.addRobot()
            emu2.runFor(29.milliseconds)
            val a = r2.trueWheelDistances.leftM
            emu2.runFor(2.milliseconds)
            val v30 = (r2.trueWheelDistances.leftM - a) / 0.002
            assertTrue(abs(v30 / vFinal - 0.63) < 0.05, "speed at 30 ms is ${v30 / vFinal} of final $vFinal m/s")
        }
    }

    @Test
    fun `the line sensor sees the line under the middle spots`() = emulator().use { emu ->
        val r = emu.addRobot(pose = Pose.ofDegrees(0.12, 0.15, 0.0))
        // Stop it from driving away: the stand-in drives PWM 500, so read right after boot.
        emu.step(1)
        val s = r.standInState()
        // Detectors 1 and 2 sit over spots 2..5 (the line is 8 mm wide, spots 2.5 mm apart): dark; 0 and 3 light.
        assertTrue(s.adc[1] > 2500 && s.adc[2] > 2500, "middle detectors ${s.adc.toList()}")
        assertTrue(s.adc[0] < 1200 && s.adc[3] < 1200, "outer detectors ${s.adc.toList()}")
    }

    @Test
    fun `two robots facing each other hear each other on the front receiver`() = emulator().use { emu ->
        val a = emu.addRobot(id = 1, pose = Pose.ofDegrees(0.3, 0.15, 0.0))
        val b = emu.addRobot(id = 2, pose = Pose.ofDegrees(0.4, 0.15, 180.0))
        emu.runFor(45.milliseconds)
        val sa = a.standInState(); val sb = b.standInState()
        assertTrue(sa.irHeard > 0 && sb.irHeard > 0, "heard ${sa.irHeard} / ${sb.irHeard}")
        assertEquals(2, sa.irSender); assertEquals(0, sa.irSide); assertEquals(0, sa.irLed)
        assertEquals(1, sb.irSender); assertEquals(0, sb.irSide)
    }

    @Test
    fun `a robot facing the box hears its own reflection`() = emulator("box").use { emu ->
        val r = emu.addRobot(id = 5, pose = Pose.ofDegrees(0.43, 0.2, 0.0))
        emu.runFor(45.milliseconds)
        val s = r.standInState()
        assertTrue(s.irHeard > 0, "no reflection heard")
        assertEquals(5, s.irSender, "reflection carries the robot's own id")
    }

    @Test
    fun `frames pass the link both ways through the in-process transport`() = emulator().use { emu ->
        val r = emu.addRobot()
        val t = r.openTransport()
        val frame = Frames.encode(Heartbeat, 0)
        runBlocking { t.send(frame) }
        emu.runFor(20.milliseconds)
        val back = runBlocking { withTimeout(10_000) { t.incoming.receive() } }
        assertContentEquals(frame, back, "the stand-in echoes what it receives")
        assertEquals(frame.size + 2, r.standInState().rxCount, "SLIP adds two END bytes")
        t.close()
    }

    @Test
    fun `the link delivers bytes at the baud rate after the latency`() = emulator().use { emu ->
        val r = emu.addRobot()
        r.link = LinkSettings(baud = 9600, latency = 5.milliseconds)
        val t = r.openTransport()
        val frame = Frames.encode(Heartbeat, 0) // 5 bytes + 2 SLIP ENDs = 7 bytes = 7.3 ms at 9600 baud
        runBlocking { t.send(frame) }
        emu.runFor(12.milliseconds)
        assertTrue(r.standInState().rxCount < 7, "all bytes arrived before baud + latency allowed")
        emu.runFor(2.milliseconds)
        assertEquals(7, r.standInState().rxCount)
        t.close()
    }

    @Test
    fun `a disconnected link loses the transport and refuses new ones until reconnected`() = emulator().use { emu ->
        val r = emu.addRobot()
        val t = r.openTransport()
        r.disconnectLink()
        val closed = runBlocking { t.incoming.receiveCatching() }
        assertTrue(closed.isClosed, "transport still open after disconnect")
        assertTrue(runCatching { r.openTransport() }.isFailure, "opened while the link is down")
        r.reconnectLink()
        r.openTransport().close()
    }

    @Test
    fun `the same world and seed give the same state hash, another seed does not`() {
        fun hash(seed: Long) = emulator("round", seed).use { emu ->
            repeat(3) { emu.addRobot() }
            emu.runFor(300.milliseconds)
            emu.stateHash()
        }
        assertEquals(hash(3), hash(3))
        assertTrue(hash(3) != hash(4))
    }

    @Test
    fun `parallel stepping gives the same result as one thread`() {
        fun hash(threads: Int) = Emulator(Worlds.load("round"), EmulatorConfig(seed = 9, firmware = standIn, threads = threads, parallelFrom = 1)).use { emu ->
            repeat(40) { emu.addRobot() }
            emu.runFor(100.milliseconds)
            emu.stateHash()
        }
        assertEquals(hash(1), hash(2))
    }

    @Test
    fun `a lossy link drops bytes and a jittery one keeps their order`() = emulator().use { emu ->
        val r = emu.addRobot()
        val t = r.openTransport()
        r.link = LinkSettings(lossRate = 1.0)
        runBlocking { t.send(Frames.encode(Heartbeat, 0)) }
        emu.runFor(20.milliseconds)
        assertEquals(0, r.standInState().rxCount, "bytes passed a link that loses everything")
        r.link = LinkSettings(latency = 3.milliseconds, jitter = 4.milliseconds)
        val frames = List(20) { Frames.encode(org.pocketbot.protocol.MovementDone(it + 1, 0, it * 0.01f), it) }
        runBlocking { frames.forEach { t.send(it) } }
        emu.runFor(100.milliseconds)
        val echoed = List(20) { runBlocking { withTimeout(10_000) { t.incoming.receive() } } }
        for (k in frames.indices) assertContentEquals(frames[k], echoed[k], "frame $k out of order or damaged")
        t.close()
    }

    @Test
    fun `the link holds at most its buffer of host bytes and counts the rest`() = emulator().use { emu ->
        val r = emu.addRobot()
        r.link = LinkSettings(bufferBytes = 100)
        r.hostSendRaw(ByteArray(60) { 1 })
        r.hostSendRaw(ByteArray(60) { 2 }) // 40 of these fit
        r.hostSendRaw(ByteArray(900) { 3 }) // none
        assertEquals(920L, r.linkBytesOverflowed)
        emu.runFor(100.milliseconds) // 100 bytes take 8.7 ms at 115200 Bd
        assertEquals(100, r.standInState().rxCount, "what fitted reached the robot")
        r.hostSendRaw(ByteArray(100) { 4 }) // the buffer drained: room again
        emu.runFor(100.milliseconds)
        assertEquals(200, r.standInState().rxCount)
        assertEquals(920L, r.linkBytesOverflowed)
    }
}

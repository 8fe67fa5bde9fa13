package org.pocketbot.emulator

import org.pocketbot.emulator.firmware.FirmwareImage
import org.pocketbot.sdk.Pose
import org.pocketbot.emulator.link.LinkSettings
import org.pocketbot.emulator.world.Box
import org.pocketbot.emulator.world.Point
import org.pocketbot.emulator.world.Tape
import org.pocketbot.emulator.world.TapeColour
import org.pocketbot.emulator.world.World
import org.pocketbot.protocol.Ack
import org.pocketbot.protocol.LineFollow
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.SyncMode
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertNotEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

class DeterminismAndFaultsTest {
    private fun run(seed: Long): String = RealFirmware.emulator("round", seed).use { emu ->
        val hosts = List(3) { TestHost(emu.addRobot()) }
        emu.runFor(50.milliseconds)
        hosts.forEach { it.send(LineFollow(1, 0, 0f)) }
        emu.runFor(2.seconds)
        hosts.forEach { it.close() }
        emu.stateHash()
    }

    @Test
    fun `two runs of the same world and seed produce identical state hashes`() {
        val first = run(7)
        assertEquals(first, run(7), "same seed, different runs")
        assertNotEquals(first, run(8), "a different seed changed nothing")
    }

    @Test
    fun `a fleet gives the same state hash on one thread or two, its firmware run natively or by Chicory`() {
        // 24 robots on the round track, close enough to hear each other's IR and to collide.
        fun hash(image: FirmwareImage, threads: Int) = Emulator(
            org.pocketbot.emulator.world.Worlds.load("round"),
            EmulatorConfig(seed = 11, firmware = image, threads = threads, parallelFrom = 1),
        ).use { emu ->
            val hosts = List(24) { k ->
                val a = Math.toRadians(k * 15.0)
                TestHost(emu.addRobot(pose = Pose.ofDegrees(0.4 + 0.3 * kotlin.math.cos(a), 0.4 + 0.3 * kotlin.math.sin(a), k * 15.0 + 90)))
            }
            hosts.forEach { it.send(LineFollow(1, 0, 0f)) }
            emu.runFor(1.5.seconds)
            hosts.forEach { it.close() }
            emu.stateHash()
        }
        val native = hash(RealFirmware.native, 1)
        assertEquals(native, hash(RealFirmware.native, 2), "native, two threads against one")
        assertEquals(native, hash(RealFirmware.chicory, 1), "Chicory against native, one thread")
        assertEquals(native, hash(RealFirmware.chicory, 2), "Chicory against native, two threads")
    }

    @Test
    fun `robots out of everyone's reach stepped in blocks end exactly as in single steps`() {
        // A line with a box across it that a robot drives up to, and a round track beside it with three robots far
        // apart and a fourth 10 cm behind one of them (within IR range): some robots are alone (they run blocks of
        // steps in a row), two are not, and the first stops being alone as it nears the box.
        val world = World(
            name = "blocks", widthM = 2.2, heightM = 0.8,
            tapes = listOf(
                Tape.Polyline(listOf(Point(0.05, 0.2), Point(0.95, 0.2)), widthM = 0.008, colour = TapeColour.BLACK),
                Tape.Arc(Point(1.6, 0.4), radiusM = 0.3, startDeg = 0.0, sweepDeg = 360.0, widthM = 0.008, colour = TapeColour.BLACK),
            ),
            boxes = listOf(Box(Point(0.5, 0.2), widthM = 0.04, heightM = 0.09)),
        )
        val poses = listOf(
            Pose.ofDegrees(0.2, 0.2, 0.0),
            Pose.ofDegrees(1.6, 0.1, 0.0), Pose.ofDegrees(1.85981, 0.55, 120.0), Pose.ofDegrees(1.34019, 0.55, 240.0),
            Pose.ofDegrees(1.5018, 0.1165, -19.1),
        )
        fun hash(blocks: Boolean) = Emulator(world, EmulatorConfig(seed = 3, firmware = RealFirmware.image, threads = 2, parallelFrom = 1)).use { emu ->
            val hosts = poses.map { TestHost(emu.addRobot(pose = it)) }
            hosts.forEach { it.send(LineFollow(1, 0, 0f)) }
            val alone = emu.sim.markAlone(8)
            assertEquals(3, alone, "robots alone at the start")
            if (blocks) emu.runFor(2.seconds) else emu.step(2000)
            hosts.forEach { it.close() }
            emu.stateHash()
        }
        assertEquals(hash(blocks = false), hash(blocks = true))
    }

    @Test
    fun `a corrupting link damages frames that the firmware counts and drops`() = RealFirmware.emulator("straight", seed = 5).use { emu ->
        val robot = emu.addRobot()
        robot.link = LinkSettings(corruptionRate = 0.02)
        TestHost(robot).use { host ->
            emu.runFor(50.milliseconds)
            val sent = 100
            repeat(sent) {
                host.send(SetSync(SyncMode.NONE.code, 100))
                emu.runFor(5.milliseconds)
            }
            emu.runFor(200.milliseconds)
            host.drain()
            val errors = robot.state().errors
            val acks = host.packets.count { it is Ack }
            println("corrupting link: $sent frames sent, $acks acked, robot errors $errors, host saw ${host.errors.size} bad frames, " +
                "${robot.linkBytesCorrupted} bytes corrupted")
            assertTrue(robot.linkBytesCorrupted > 0, "the link corrupted nothing")
            assertTrue(errors.crc > 0, "the firmware counted no CRC errors: $errors")
            assertTrue(errors.crc + errors.framing + errors.rejected <= sent, "more errors than frames: $errors")
            assertTrue(acks < sent, "every frame was acknowledged despite corruption")
            assertTrue(acks > sent / 2, "too few frames got through: $acks")
            assertTrue(host.errors.isNotEmpty(), "robot-to-host frames were corrupted too, the host's decoder saw none")
        }
    }

    @Test
    fun `a clean link loses nothing`() = RealFirmware.emulator("straight", seed = 5).use { emu ->
        val robot = emu.addRobot()
        TestHost(robot).use { host ->
            emu.runFor(50.milliseconds)
            val seqs = List(50) { host.send(SetSync(SyncMode.NONE.code, 100)).also { emu.runFor(5.milliseconds) } }
            emu.runFor(100.milliseconds)
            host.drain()
            // Each command acknowledged exactly once (the handshake's set_role has an ack of its own).
            val acked = host.received.filter { it.second is Ack }.map { it.first }
            assertEquals(seqs, acked.filter { it in seqs })
            assertEquals(acked.distinct(), acked)
            assertEquals(0, robot.state().errors.crc)
        }
    }
}

package org.pocketbot.emulator

import org.pocketbot.sdk.Pose
import org.pocketbot.emulator.link.LinkSettings
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
    fun `a fleet stepped on one thread or on several gives the same state hash`() {
        fun hash(threads: Int) = Emulator(
            org.pocketbot.emulator.world.Worlds.load("round"),
            EmulatorConfig(seed = 11, firmware = RealFirmware.image, threads = threads, parallelFrom = 1),
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
        assertEquals(hash(1), hash(2))
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

package org.pocketbot.emulator

import org.pocketbot.emulator.physics.Obb
import org.pocketbot.emulator.physics.RobotParams
import org.pocketbot.emulator.world.Surface
import org.pocketbot.emulator.world.World
import org.pocketbot.emulator.world.Worlds
import org.pocketbot.sdk.Pose
import kotlin.math.hypot
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

/** Where robots added without a pose stand: never on another robot, and a clear error when the floor is full. */
class PlacementTest {
    private val params = RobotParams()

    private fun bodiesTouch(a: Pose, b: Pose): Boolean {
        val pa = Obb().set(a.xM, a.yM, a.headingRad, params.lengthM / 2, params.widthM / 2)
        val pb = Obb().set(b.xM, b.yM, b.headingRad, params.lengthM / 2, params.widthM / 2)
        return pa.overlap(pb, DoubleArray(3))
    }

    @Test
    fun `robots beyond a world's start poses stand on free floor off the tape, and never touch`() =
        Emulator(Worlds.load("straight"), EmulatorConfig(firmware = RealFirmware.image)).use { emu ->
            repeat(5) { emu.addRobot() }
            val poses = emu.robots.map { it.truePose }
            val starts = emu.world.starts.map { it.toPose() }
            assertEquals(starts, poses.take(2), "the first robots stand at the world's start poses")
            val surface = Surface(emu.world)
            for (p in poses.drop(2)) {
                assertTrue(surface.distanceToTapeEdge(p.xM, p.yM) > hypot(params.lengthM, params.widthM) / 2, "robot at $p stands on the tape")
            }
            for (i in poses.indices) for (j in i + 1 until poses.size) {
                assertTrue(!bodiesTouch(poses[i], poses[j]), "robots ${i + 1} and ${j + 1} overlap at ${poses[i]} and ${poses[j]}")
            }
            emu.runFor(100.milliseconds)
            assertEquals(0L, emu.robotContacts, "robots were pushed apart, so some stood on others")
        }

    @Test
    fun `a start pose a robot already stands on is skipped`() =
        Emulator(Worlds.load("round"), EmulatorConfig(firmware = RealFirmware.image)).use { emu ->
            val starts = emu.world.starts.map { it.toPose() }
            emu.addRobot(pose = starts[0])
            assertEquals(starts[1], emu.addRobot().truePose)
        }

    @Test
    fun `a floor with no room left says so instead of stacking robots`() {
        val tiny = World(name = "tiny", widthM = 0.1, heightM = 0.1)
        Emulator(tiny, EmulatorConfig(firmware = RealFirmware.image)).use { emu ->
            emu.addRobot()
            val e = assertFailsWith<IllegalStateException> { emu.addRobot() }
            assertTrue("no room for another robot in world tiny" in e.message!!, "message: ${e.message}")
            assertEquals(1, emu.robots.size, "a robot was added although there was no room")
            emu.addRobot(pose = Pose(0.05, 0.05, 0.0)) // a robot given a pose is placed where asked
            assertEquals(2, emu.robots.size)
        }
    }
}

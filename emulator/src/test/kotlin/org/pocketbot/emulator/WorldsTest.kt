package org.pocketbot.emulator

import org.pocketbot.sdk.Pose
import org.pocketbot.emulator.world.Surface
import org.pocketbot.emulator.world.TapeColour
import org.pocketbot.emulator.world.World
import org.pocketbot.emulator.world.Worlds
import org.pocketbot.protocol.LineFollow
import org.pocketbot.protocol.LineFollowStatus
import kotlin.math.cos
import kotlin.math.sin
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

class WorldsTest {
    @Test
    fun `every shipped world loads, survives a JSON round trip and starts its robots on the line`() {
        for (name in Worlds.names) {
            val w = Worlds.load(name)
            assertEquals(w.toJson(), World.fromJson(w.toJson()).toJson(), "$name JSON round trip")
            val surface = Surface(w)
            assertTrue(w.starts.isNotEmpty(), "$name has no start poses")
            if (w.tapes.isEmpty()) continue // the open floor
            for (s in w.starts) {
                val h = Math.toRadians(s.headingDeg)
                val dark = surface.irDarkness(s.xM + 0.02 * cos(h), s.yM + 0.02 * sin(h), 0.0012)
                assertTrue(dark > 0.5, "$name: the line sensor of a robot at $s sees darkness $dark, not the line")
            }
        }
    }

    @Test
    fun `the open floor has no tape, and a 30 cm square driven to the left from a start stays clear of the others`() {
        val w = Worlds.load("open")
        assertTrue(w.tapes.isEmpty() && w.boxes.isEmpty())
        val robotHalfDiagonal = 0.029
        for (a in w.starts) for (b in w.starts) if (a !== b) {
            // The square spans x .. x + 0.3 and y .. y + 0.3 from its start; another robot at b must stay out of it.
            val clear = b.xM + robotHalfDiagonal < a.xM - robotHalfDiagonal || b.xM - robotHalfDiagonal > a.xM + 0.3 + robotHalfDiagonal ||
                b.yM + robotHalfDiagonal < a.yM - robotHalfDiagonal || b.yM - robotHalfDiagonal > a.yM + 0.3 + robotHalfDiagonal
            assertTrue(clear, "the square from $a reaches the robot at $b")
        }
        for (s in w.starts) {
            assertTrue(s.xM + 0.3 + robotHalfDiagonal < w.widthM && s.yM + 0.3 + robotHalfDiagonal < w.heightM, "the square from $s leaves the floor")
        }
    }

    @Test
    fun `the floor is white, black tape is black, and a spot half on the tape is half dark`() {
        val s = Surface(Worlds.load("straight"))
        assertEquals(0.0, s.irDarkness(0.5, 0.25, 0.0012), 1e-9)
        assertEquals(1.0, s.irDarkness(0.5, 0.15, 0.0012), 1e-9)
        assertEquals(0.5, s.irDarkness(0.5, 0.154, 0.0012), 1e-9) // the 8 mm tape's edge
        val c = Surface(Worlds.load("colours"))
        assertEquals(TapeColour.RED, c.tapeAt(0.4 + 0.3 * cos(Math.toRadians(30.0)), 0.4 + 0.3 * sin(Math.toRadians(30.0))))
        assertEquals(TapeColour.BLUE, c.tapeAt(0.4 + 0.3 * cos(Math.toRadians(210.0)), 0.4 + 0.3 * sin(Math.toRadians(210.0))))
        assertEquals(TapeColour.BLACK, c.tapeAt(0.4 + 0.3 * cos(Math.toRadians(120.0)), 0.4 + 0.3 * sin(Math.toRadians(120.0))))
    }

    @Test
    fun `distances to the tape's edge, and a box on the tape is 0 mm off it`() {
        val s = Surface(Worlds.load("straight"))
        assertTrue(s.distanceToTapeEdge(0.5, 0.15) <= 0.0, "on the tape")
        assertEquals(0.046, s.distanceToTapeEdge(0.5, 0.2), 1e-4) // 50 mm from the centre line, 4 mm half width
        RealFirmware.emulator("push").use { emu -> assertEquals(0.0, emu.boxClearanceM()) }
    }

    @Test
    fun `the firmware follows the figure-eight through its crossing`() = RealFirmware.emulator("figure-eight").use { emu ->
        val robot = emu.addRobot()
        val surface = Surface(emu.world)
        TestHost(robot).use { host ->
            host.send(LineFollow(1, 0, 0f))
            var worst = 0.0
            var t = 0
            var crossings = 0
            var nearCentre = false
            while (t < 16_000) {
                host.run(10.milliseconds); t += 10
                val p = robot.truePose
                worst = maxOf(worst, surface.distanceToTape(p.xM, p.yM))
                val c = kotlin.math.hypot(p.xM - 0.45, p.yM - 0.3) < 0.01
                if (c && !nearCentre) crossings++
                nearCentre = c
            }
            assertEquals(LineFollowStatus.FOLLOWING, robot.state().lineFollow.status)
            assertTrue(crossings >= 2, "crossed the middle $crossings times in 16 s")
            assertTrue(worst < 0.006, "robot strayed ${worst * 1000} mm from the track")
        }
    }

    /** Follows the fork world's line at [speedMps] (0: the default); returns where the robot ended, its worst
     *  distance from the tape on the way, and whether the follower reported the line lost before a branch's end. */
    private fun followFork(seed: Long, speedMps: Float): Triple<Pose, Double, Boolean> =
        RealFirmware.emulator("fork", seed).use { emu ->
            val robot = emu.addRobot()
            val surface = Surface(emu.world)
            TestHost(robot).use { host ->
                host.send(LineFollow(1, 0, speedMps))
                var worst = 0.0
                var lostEarly = false
                repeat(900) {
                    host.run(10.milliseconds)
                    val p = robot.truePose
                    if (p.xM < 0.95 && p.yM < 0.55) {
                        worst = maxOf(worst, surface.distanceToTape(p.xM, p.yM))
                        lostEarly = lostEarly || robot.state().lineFollow.status == LineFollowStatus.LOST
                    }
                }
                Triple(robot.truePose, worst, lostEarly)
            }
        }

    @Test
    fun `at the fork the firmware follows one branch to its end`() {
        val (end, worst, lostEarly) = followFork(1, 0f)
        assertTrue(end.xM > 0.95 || end.yM > 0.55, "robot stopped at $end, not at the end of a branch")
        assertTrue(!lostEarly, "the line was lost before a branch's end")
        assertTrue(worst < 0.0045, "robot strayed ${worst * 1000} mm from the tape")
    }

    /**
     * At a Y fork the line position of both branches together lies between them: a follower that steers there
     * loses both. The firmware commits to one branch as soon as the sensor sees two lines, so the robot never
     * strays far from the tape (5.6 mm at the fork, and lost in some runs, before it did).
     */
    @Test
    fun `at two and three times the default speed the firmware takes one branch of the fork decisively, whatever the seed`() {
        for ((speed, seeds) in listOf(0.30f to 1L..6L, 0.45f to 1L..3L)) for (seed in seeds) {
            val (end, worst, lostEarly) = followFork(seed, speed)
            val branch = if (end.yM > 0.55) "left" else if (end.xM > 0.95) "straight" else "none"
            println("fork at $speed m/s, seed $seed: ended at $end ($branch branch), worst ${"%.2f".format(worst * 1000)} mm off the tape")
            assertTrue(branch != "none", "$speed m/s, seed $seed: robot stopped at $end, not at the end of a branch")
            assertTrue(!lostEarly, "$speed m/s, seed $seed: the line was lost before a branch's end")
            assertTrue(worst < 0.0045, "$speed m/s, seed $seed: robot strayed ${worst * 1000} mm from the tape")
        }
    }
}

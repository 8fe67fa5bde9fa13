package org.pocketbot.emulator

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
            assertEquals(w, World.fromJson(w.toJson()), "$name JSON round trip")
            val surface = Surface(w)
            assertTrue(w.starts.isNotEmpty(), "$name has no start poses")
            for (s in w.starts) {
                val h = Math.toRadians(s.headingDeg)
                val dark = surface.irDarkness(s.x + 0.02 * cos(h), s.y + 0.02 * sin(h), 0.0012)
                assertTrue(dark > 0.5, "$name: the line sensor of a robot at $s sees darkness $dark, not the line")
            }
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
                worst = maxOf(worst, surface.distanceToTape(p.x, p.y))
                val c = kotlin.math.hypot(p.x - 0.45, p.y - 0.3) < 0.01
                if (c && !nearCentre) crossings++
                nearCentre = c
            }
            assertEquals(LineFollowStatus.FOLLOWING.code, robot.state().lineFollow.status)
            assertTrue(crossings >= 2, "crossed the middle $crossings times in 16 s")
            assertTrue(worst < 0.006, "robot strayed ${worst * 1000} mm from the track")
        }
    }

    @Test
    fun `at the fork the firmware follows one branch to its end`() = RealFirmware.emulator("fork").use { emu ->
        val robot = emu.addRobot()
        val surface = Surface(emu.world)
        TestHost(robot).use { host ->
            host.send(LineFollow(1, 0, 0f))
            var worst = 0.0
            repeat(900) { host.run(10.milliseconds); val p = robot.truePose; if (p.x < 0.95) worst = maxOf(worst, surface.distanceToTape(p.x, p.y)) }
            val end = robot.truePose
            assertTrue(end.x > 0.95 || end.y > 0.55, "robot stopped at $end, not at the end of a branch")
            assertTrue(worst < 0.006, "robot strayed ${worst * 1000} mm from the tape")
        }
    }
}

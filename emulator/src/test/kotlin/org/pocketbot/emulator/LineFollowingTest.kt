package org.pocketbot.emulator

import org.pocketbot.protocol.LineFollow
import org.pocketbot.protocol.LineFollowStatus
import kotlin.math.PI
import kotlin.math.abs
import kotlin.math.max
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/** The real firmware follows lines in the simulated worlds. */
class LineFollowingTest {
    @Test
    fun `a robot on the straight line follows it to the end`() = RealFirmware.emulator("straight").use { emu ->
        val robot = emu.addRobot()
        TestHost(robot).use { host ->
            host.send(LineFollow(1, 0, 0f))
            var maxOffset = 0.0
            var t = 0
            while (t < 9000) { // the 1 m line takes ~6.5 s at the default 0.15 m/s
                emu.runFor(10.milliseconds); t += 10
                val p = robot.truePose
                if (p.xM < 1.09) maxOffset = max(maxOffset, abs(p.yM - 0.15))
            }
            val end = robot.truePose
            val state = robot.state()
            assertTrue(end.xM > 1.09, "robot stopped at x=${end.xM}, before the line's end at 1.10")
            assertTrue(maxOffset < 0.002, "robot strayed ${maxOffset * 1000} mm from the line")
            assertEquals(LineFollowStatus.LOST, state.lineFollow.status, "line follower after the end: ${state.lineFollow}")
            assertEquals(0 to 0, robot.pwmPermille, "motors stopped after the line was lost")
        }
    }

    @Test
    fun `a robot laps the round track without losing the line`() = RealFirmware.emulator("round").use { emu ->
        val robot = emu.addRobot()
        val cx = 0.4; val cy = 0.4; val r = 0.3
        TestHost(robot).use { host ->
            host.send(LineFollow(1, 0, 0f))
            var angle = 0.0
            var prev = robot.truePose.let { polarAngle(it.xM, it.yM, cx, cy) }
            var maxRadial = 0.0
            var t = 0
            while (angle < 2 * PI && t < 20_000) {
                emu.runFor(10.milliseconds); t += 10
                val p = robot.truePose
                val a = polarAngle(p.xM, p.yM, cx, cy)
                angle += unwrap(prev, a); prev = a
                maxRadial = max(maxRadial, abs(radius(p.xM, p.yM, cx, cy) - r))
                val s = robot.state()
                assertEquals(LineFollowStatus.FOLLOWING, s.lineFollow.status, "at t=$t ms, ${angle / PI * 180} deg: ${s.line}")
            }
            assertTrue(angle >= 2 * PI, "one lap not done in ${t / 1000.0} s: ${angle / PI * 180} deg")
            assertTrue(maxRadial < 0.004, "robot strayed ${maxRadial * 1000} mm from the track")
            println("round lap: ${t / 1000.0} s, largest radial error ${"%.2f".format(maxRadial * 1000)} mm")
        }
    }

    @Test
    fun `on the colour track the robot slows on red and speeds up on blue`() = RealFirmware.emulator("colours").use { emu ->
        val robot = emu.addRobot()
        val cx = 0.4; val cy = 0.4
        TestHost(robot).use { host ->
            host.send(LineFollow(1, 1, 0f))
            val speeds = HashMap<String, MutableList<Double>>()
            var prev = robot.trueWheelDistances
            var t = 0
            while (t < 14_000) {
                emu.runFor(100.milliseconds); t += 100
                val w = robot.trueWheelDistances
                val v = ((w.leftM + w.rightM) - (prev.leftM + prev.rightM)) / 2 / 0.1
                prev = w
                val p = robot.truePose
                val deg = Math.toDegrees(polarAngle(p.xM, p.yM, cx, cy)).let { if (it < 0) it + 360 else it }
                val zone = when { deg in 20.0..60.0 -> "red"; deg in 200.0..240.0 -> "blue"; deg in 100.0..160.0 || deg in 280.0..340.0 -> "black"; else -> null }
                if (zone != null) speeds.getOrPut(zone) { ArrayList() } += v
            }
            val mean = speeds.mapValues { it.value.average() }
            println("colour segments, mean speed m/s: $mean")
            assertTrue(mean.getValue("red") < mean.getValue("black") - 0.03, "red is not slower: $mean")
            assertTrue(mean.getValue("blue") > mean.getValue("black") + 0.03, "blue is not faster: $mean")
        }
    }
}

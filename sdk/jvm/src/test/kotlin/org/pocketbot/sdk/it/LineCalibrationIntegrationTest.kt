package org.pocketbot.sdk.it

import kotlinx.coroutines.delay
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.sdk.LineCalibration
import org.pocketbot.sdk.LineCalibrator
import org.pocketbot.sdk.LineFollowStatus
import org.pocketbot.sdk.Pose
import org.pocketbot.sdk.Robot
import kotlin.math.PI
import kotlin.math.abs
import kotlin.math.atan2
import kotlin.math.hypot
import kotlin.test.assertEquals
import kotlin.test.assertFalse
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * Line sensor calibration on the real firmware, on the round track (a circle of 0.3 m radius around (0.4, 0.4)). The
 * emulated spots read about 110 ADC counts over the white floor and 2010 over black tape (ambient light suppressed).
 */
class LineCalibrationIntegrationTest {
    @Test
    fun aSweepFromWrongValuesGivesACalibrationWithWhichTheRobotLapsTheTrack() = withEmulator(world = "round", limit = 90.seconds) { emu ->
        val robot = connectAll(emu).single()
        val handle = emu.handleOf(robot)
        val start = handle.truePose
        val sensor = robot.settings.lineSensor
        // Wrong values: every reading is "whiter than white", so no spot ever sees the line.
        sensor.calMin.set(List(8) { 3000 })
        sensor.calMax.set(List(8) { 4000 })
        robot.lineFollower.start()
        delay(1.seconds)
        assertEquals(LineFollowStatus.LOST, robot.lineFollower.followStatus, "with the wrong calibration the line is lost")
        handle.place(start)

        val calibrator = LineCalibrator(robot)
        val calibration = calibrator.sweep()
        assertTrue(calibration.isUsable, "weak spots ${calibration.weakSpots} in $calibration")
        assertTrue(calibration.white.all { it in 60..180 }, "white readings $calibration")
        assertTrue(calibration.black.all { it in 1850..2000 }, "black readings $calibration")
        assertEquals(null, calibrator.progress.value, "no sweep runs any more")
        assertTrue(angleBetween(start.headingRad, handle.truePose.headingRad) < 10 * PI / 180, "the sweep ends facing about as it began: ${handle.truePose}, odometry ${robot.odometry.pose.value}")

        calibrator.apply(calibration)
        assertEquals(calibration.white, sensor.calMin.value)
        assertEquals(calibration.black, sensor.calMax.value)
        assertEquals(calibration.white, valueIn(handle.settingsBytes(), "line_sensor.cal_min"), "the robot holds the new values")
        assertEquals(calibration.black, valueIn(handle.settingsBytes(), "line_sensor.cal_max"))

        val lap = lap(robot, handle)
        assertTrue(lap.completed, "one lap with the calibration: $lap")
        assertTrue(lap.maxRadialErrorM < 0.004, "the robot strayed ${lap.maxRadialErrorM * 1000} mm from the tape")
        robot.lineFollower.stop()
        robot.close()
    }

    @Test
    fun byHandTheRobotIsSampledOnWhiteThenAcrossTheLine() = withEmulator(world = "round") { emu ->
        val robot = connectAll(emu).single()
        val handle = emu.handleOf(robot)
        val calibrator = LineCalibrator(robot)
        handle.place(Pose.ofDegrees(0.4, 0.4, 0.0)) // the middle of the circle: white floor
        val white = calibrator.sample()
        // Facing the centre 2 cm below the tape: the sensor row (2 cm ahead of the axle) lies along the tape.
        handle.place(Pose.ofDegrees(0.4, 0.08, 90.0))
        val black = calibrator.sample()
        val calibration = LineCalibration(white, black)
        assertTrue(white.all { it in 90..130 }, "white $white")
        assertTrue(black.all { it in 1850..1950 }, "black $black")
        assertTrue(calibration.isUsable)

        handle.place(Pose.ofDegrees(0.4, 0.4, 0.0))
        val flat = LineCalibration(white, calibrator.sample())
        assertFalse(flat.isUsable, "white twice is no calibration")
        assertEquals((0 until 8).toList(), flat.weakSpots)
        robot.close()
    }

    private class Lap(val completed: Boolean, val maxRadialErrorM: Double, val seconds: Double) {
        override fun toString() = "lap completed=$completed in $seconds s, largest radial error ${maxRadialErrorM * 1000} mm"
    }

    /** Follows the line for up to 20 s of simulated time, measuring the true pose against the circle every 10 ms. */
    private suspend fun lap(robot: Robot, handle: RobotHandle): Lap {
        robot.lineFollower.start()
        var turned = 0.0
        var prev = polar(handle.truePose)
        var maxRadial = 0.0
        var ms = 0
        while (turned < 2 * PI && ms < 20_000) {
            delay(10.milliseconds)
            ms += 10
            val p = handle.truePose
            val a = polar(p)
            turned += unwrap(a - prev)
            prev = a
            maxRadial = maxOf(maxRadial, abs(hypot(p.xM - 0.4, p.yM - 0.4) - 0.3))
        }
        return Lap(turned >= 2 * PI, maxRadial, ms / 1000.0)
    }

    private fun polar(p: Pose) = atan2(p.yM - 0.4, p.xM - 0.4)
    private fun unwrap(d: Double) = when { d > PI -> d - 2 * PI; d < -PI -> d + 2 * PI; else -> d }
    private fun angleBetween(a: Double, b: Double) = abs(unwrap(a - b))
}

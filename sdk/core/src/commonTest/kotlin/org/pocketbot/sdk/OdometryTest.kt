package org.pocketbot.sdk

import kotlinx.coroutines.flow.first
import kotlinx.coroutines.launch
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.StateEncoders
import org.pocketbot.protocol.StateTime
import kotlin.math.PI
import kotlin.math.abs
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue

class OdometryTest {
    private var t = 0L
    private fun ScriptedRobot.encoders(left: Int, right: Int) = sendState(WIRE_EMPTY.with(time = StateTime(++t, 0, 0, 0), encoders = StateEncoders(left, right)))

    // Defaults: wheel 9 mm, base 26 mm, 40 pulses per revolution, as float32 (as the robot holds them).
    private val diameter = Float.fromBits(0.009f.toRawBits()).toDouble()
    private val base = Float.fromBits(0.026f.toRawBits()).toDouble()
    private val perPulse = PI * diameter / 40

    @Test
    fun straightDrivingAdvancesAlongX() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.encoders(1000, 1000) // the first state is the zero, whatever the counts
        peer.encoders(1040, 1040)
        val pose = robot.odometry.pose.first { it.xM > 0 }
        assertEquals(40 * perPulse, pose.xM, 1e-9)
        assertEquals(0.0, pose.yM, 1e-12)
        assertEquals(0.0, pose.headingRad, 1e-12)
        robot.close()
    }

    @Test
    fun headingComesFromTheTotalCountDifference() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.encoders(0, 0)
        // a quarter turn in place, in many small uneven steps
        var l = 0
        var r = 0
        repeat(50) { i ->
            l -= if (i % 3 == 0) 1 else 0
            r += if (i % 2 == 0) 1 else 0
            peer.encoders(l, r)
        }
        val expected = perPulse / base * (r - l)
        robot.state.first { it.time.timeMs == t }
        val pose = robot.odometry.pose.value
        assertTrue(abs(pose.headingRad - expected) < 1e-12, "heading ${pose.headingRad} != $expected")
        robot.close()
    }

    @Test
    fun headingAfterManyTurnsThereAndBackIsExactlyZero() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.encoders(0, 0)
        // Hundreds of turns in place and back in small steps: a sum of heading increments collects rounding
        // error at every step (the heading grows to thousands of radians), the total-count formula has none.
        var l = 0
        var r = 0
        val steps = 20_000
        repeat(steps) { l -= 7; r += 7; peer.encoders(l, r) }
        repeat(steps) { l += 7; r -= 7; peer.encoders(l, r) }
        robot.state.first { it.time.timeMs == t }
        assertEquals(0.0, robot.odometry.pose.value.headingRad, "heading after returning to the start counts")
        robot.close()
    }

    @Test
    fun headingIsWrappedToMinusPiPi() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.encoders(0, 0)
        // Left on the spot, one pulse per wheel per state, through one and a quarter turns: the pose reads -pi..pi
        // at every step, as the emulator's ground truth does; the position never jumps where the heading wraps.
        val pulsesPerTurn = (2 * PI * base / perPulse / 2).toInt()
        val headings = mutableListOf<Double>()
        val collector = backgroundScope.launch { robot.odometry.pose.collect { headings += it.headingRad } }
        var n = 0
        repeat(pulsesPerTurn * 5 / 4) {
            n++
            peer.encoders(-n, n)
            robot.state.first { it.time.timeMs == t }
            kotlinx.coroutines.yield()
        }
        collector.cancel()
        assertTrue(headings.all { it > -PI - 1e-12 && it <= PI + 1e-12 }, "headings out of -pi..pi: ${headings.filter { abs(it) > PI }}")
        assertTrue(headings.any { it < -PI / 2 }, "a turn past pi reads negative")
        val expected = perPulse / base * 2 * n - 2 * PI
        assertEquals(expected, robot.odometry.pose.value.headingRad, 1e-9)
        assertTrue(robot.odometry.pose.value.distanceTo(Pose.ORIGIN) < 1e-9, "a turn in place does not move the robot")
        robot.close()
    }

    @Test
    fun wheelDistancesAreInMetresFromTheRobotsGeometry() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.encoders(500, 500)
        peer.encoders(540, 520)
        robot.state.first { it.time.timeMs == t }
        val w = robot.odometry.wheelDistances.value
        assertEquals(40 * perPulse, w.leftM, 1e-12)
        assertEquals(20 * perPulse, w.rightM, 1e-12)
        assertEquals(30 * perPulse, w.travelledM, 1e-12)
        robot.close()
    }

    @Test
    fun aRobotResetKeepsThePoseAndCountsOnFromItsNewZero() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.encoders(0, 0)
        peer.encoders(100, 100)
        robot.state.first { it.time.timeMs == t }
        val before = robot.odometry.pose.value
        // The robot resets: its clock and its counts start again.
        t = 0
        peer.encoders(0, 0)
        peer.encoders(40, 40)
        val after = robot.odometry.pose.first { it.xM > before.xM }
        assertEquals(before.xM + 40 * perPulse, after.xM, 1e-9)
        assertEquals(140 * perPulse, robot.odometry.wheelDistances.value.leftM, 1e-9)
        robot.close()
    }

    @Test
    fun squareEndsWhereItStarted() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.encoders(0, 0)
        val side = 142 // pulses for ~0.1 m
        val quarter = kotlin.math.round(PI / 2 * base / perPulse).toInt() // pulses of wheel difference / 2 each
        var l = 0
        var r = 0
        repeat(4) {
            repeat(side) { l++; r++; peer.encoders(l, r) }
            repeat(quarter / 2) { l--; r++; peer.encoders(l, r) }
        }
        robot.state.first { it.time.timeMs == t }
        val pose = robot.odometry.pose.value
        assertTrue(pose.distanceTo(Pose.ORIGIN) < 0.01, "square ended at $pose")
        robot.close()
    }

    @Test
    fun resetMakesTheCurrentPositionTheGivenPose() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.encoders(0, 0)
        peer.encoders(100, 100)
        robot.odometry.pose.first { it.xM > 0 }
        robot.odometry.reset(Pose(1.0, 2.0, PI))
        peer.encoders(100, 100)
        peer.encoders(140, 140)
        val pose = robot.odometry.pose.first { it.xM < 1.0 }
        assertEquals(1.0 - 40 * perPulse, pose.xM, 1e-9)
        assertEquals(2.0, pose.yM, 1e-9)
        robot.close()
    }

    @Test
    fun resetCountsFromTheLastStateNotFromTheNextOne() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.encoders(0, 0)
        peer.encoders(5, 5)
        robot.state.first { it.time.timeMs == t }
        robot.odometry.reset()
        // The robot was already turning when the next state was taken: that turn belongs to the new pose.
        peer.encoders(5 - 3, 5 + 3)
        robot.state.first { it.time.timeMs == t }
        assertEquals(perPulse / base * 6, robot.odometry.pose.value.headingRad, 1e-12)
        robot.close()
    }

    @Test
    fun geometryComesFromTheSettings() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.settings.encoder.pulsesPerRev.set(80)
        peer.encoders(0, 0)
        peer.encoders(80, 80)
        val pose = robot.odometry.pose.first { it.xM > 0 }
        assertEquals(PI * diameter, pose.xM, 1e-9)
        robot.close()
    }
}

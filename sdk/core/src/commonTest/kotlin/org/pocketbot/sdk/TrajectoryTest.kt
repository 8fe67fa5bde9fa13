package org.pocketbot.sdk

import kotlinx.coroutines.flow.first
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.StateEncoders
import org.pocketbot.protocol.StateTime
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue

class TrajectoryTest {
    @Test
    fun aRobotStandingStillAddsNothing() {
        val t = Trajectory()
        repeat(100) { t.add(it.toLong(), Pose(0.1, 0.2, 0.0)) }
        t.add(100, Pose(0.1005, 0.2, 0.0)) // half a millimetre: not yet
        assertEquals(1, t.points.value.size)
        t.add(101, Pose(0.102, 0.2, 0.0))
        assertEquals(2, t.points.value.size)
        assertEquals(0.002, t.lengthM, 1e-12)
    }

    @Test
    fun aFullTrajectoryKeepsItsShapeAtHalfTheResolutionAndSnapshotsStayAsTheyWere() {
        val t = Trajectory(capacity = 100)
        repeat(99) { t.add(it.toLong(), Pose(it * 0.01, 0.0, 0.0)) }
        val before = t.points.value
        assertEquals(99, before.size)
        repeat(50) { t.add(99L + it, Pose((99 + it) * 0.01, 0.0, 0.0)) }
        val after = t.points.value
        assertTrue(after.size <= 100, "${after.size} points")
        assertEquals(0.0, after.first().pose.xM)
        assertEquals(1.48, after.last().pose.xM, 1e-12, "the newest point is always kept")
        assertEquals(99, before.size, "a snapshot handed out never changes")
        assertEquals(0.98, before.last().pose.xM, 1e-12)
    }

    @Test
    fun csvHasAHeaderAndALinePerPoint() {
        val t = Trajectory()
        t.add(5, Pose(0.0, 0.0, 0.0))
        t.add(10, Pose(0.01, 0.02, 0.5))
        val lines = t.toCsv().trimEnd().lines()
        assertEquals("time_ms,x_m,y_m,heading_rad", lines[0])
        assertEquals(listOf(listOf(5.0, 0.0, 0.0, 0.0), listOf(10.0, 0.01, 0.02, 0.5)), lines.drop(1).map { l -> l.split(',').map { it.toDouble() } })
    }

    @Test
    fun odometryRecordsItsPathWithRobotTime() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        var time = 0L
        for (left in listOf(0, 0, 40, 80, 120)) peer.sendState(WIRE_EMPTY.with(time = StateTime(time++, 0, 0, 0), encoders = StateEncoders(left, left)))
        robot.state.first { it.time.timeMs == time - 1 }
        val points = robot.odometry.trajectory.points.value
        assertEquals(listOf(0L, 2L, 3L, 4L), points.map { it.timeMs }, "the first state is the start; standing still adds nothing")
        assertEquals(robot.odometry.pose.value, points.last().pose)
        robot.odometry.clearTrajectory()
        assertTrue(robot.odometry.trajectory.points.value.isEmpty())
        robot.close()
    }
}

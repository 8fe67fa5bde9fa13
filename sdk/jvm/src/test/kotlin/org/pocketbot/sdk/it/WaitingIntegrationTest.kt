package org.pocketbot.sdk.it

import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.Emulator
import org.pocketbot.sdk.ConnectFailedException
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.Locomotion
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.connect
import kotlin.math.abs
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue

/** Waiting that means what it says, on the real firmware: settled odometry, programs longer than the queue. */
class WaitingIntegrationTest {
    private val square = List(4) { listOf(Movement.Straight(0.10, 0.2), Movement.Rotate(90.0, 0.2)) }.flatten()

    @Test
    fun afterAwaitSettledOdometryIsWhereTheRobotStoppedAndLaterStatesSaySo() = withEmulator(world = "open") { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        robot.odometry.reset(sim.truePose)
        square.forEach { robot.locomotion.enqueue(it) }
        robot.locomotion.awaitSettled()
        val settled = robot.odometry.pose.value
        val counts = robot.state.value.encoders
        val truth = sim.truePose
        // Several state periods later, standing still: the same counts, the same pose.
        val at = robot.state.value.time.timeMs
        val later = robot.state.first { it.time.timeMs > at + 5 * robot.reflector.period.value.inWholeMilliseconds }
        assertEquals(counts.left to counts.right, later.encoders.left to later.encoders.right, "the counts the robot stopped at")
        assertEquals(settled, robot.odometry.pose.value, "odometry after awaitSettled is final")
        // One heading convention: odometry and ground truth both read -180..180 (a full turn left is about 0, not 360).
        assertTrue(abs(settled.headingDeg - truth.headingDeg) < 5, "odometry $settled beside truth $truth")
        assertTrue(settled.distanceTo(truth) < 0.01, "odometry $settled beside truth $truth")
        robot.close()
    }

    @Test
    fun runTogetherFeedsProgramsLongerThanTheRobotsQueue() = withEmulator(robots = 2, world = "open") { emu ->
        val fleet = Fleet(this, itOptions())
        val robots = fleet.discoverAndConnect(emu.discoverer(), count = 2)
        val starts = robots.associateWith { emu.handleOf(it).truePose }
        val program = square + square + square // 24 movements: more than the robot holds
        assertTrue(program.size > Locomotion.QUEUE_CAPACITY)
        val results = fleet.runTogether(robots.associateWith { program })
        fleet.awaitSettled()
        for ((robot, list) in results) {
            assertEquals(program.size, list.size, "every movement of ${robot.identity.name} ran")
            assertTrue(list.all { it.outcome == MovementOutcome.FINISHED }, "$list")
            // Three squares bring it back to where it started.
            val end = emu.handleOf(robot).truePose
            assertTrue(end.distanceTo(starts.getValue(robot)) < 0.03, "${robot.identity.name} from ${starts[robot]} to $end")
        }
        fleet.disconnect()
    }

    @Test
    fun connectingToAnEmulatorThatIsNotRunningSaysSo() = Emulator.local(robots = 1).use { emu ->
        val started = System.nanoTime()
        val e = assertFailsWith<ConnectFailedException> {
            runBlocking { emu.discoverer().discover().first().connect(this, itOptions()) }
        }
        assertTrue(e.message!!.contains("the emulator is not running") && e.message!!.contains("emulator.start()"), e.message)
        assertTrue(System.nanoTime() - started < 10_000_000_000L, "says so within seconds")
    }
}

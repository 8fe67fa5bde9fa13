package org.pocketbot.examples

import kotlinx.coroutines.async
import kotlinx.coroutines.awaitAll
import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.launch
import kotlinx.coroutines.selects.select
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.runSimulated
import org.pocketbot.sdk.DistanceClass
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotState
import org.pocketbot.sdk.SyncMode
import org.pocketbot.sdk.hearsRobot
import org.pocketbot.sdk.seesObstacle
import org.pocketbot.sdk.transport.Discoverer
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * Cooperative object manipulation (thesis A.2), coordinated by the host: two robots follow a line; a box lies on it,
 * too heavy for one robot. The first robot to reach the box sees it with its front IR (an obstacle: its own beacon
 * comes back) and stops; the second stops behind it when it hears the first close ahead. Both step aside to the
 * two halves of the box, the second creeps up until it sees the box too, and the host starts both pushes at the same
 * moment ([Fleet.enqueueTogether]): together they move the box off the track. Then they back off, return to the line
 * one after the other and follow it on, the second keeping its distance from the first.
 *
 * `make push` runs it on the emulator's `push` world (a loop whose corner the box blocks) on simulated time: repeatable,
 * a few seconds. Its last line: `box cleared: <mm> mm off the tape in <s> s`. Against real robots only the discoverer
 * changes, and the block runs in `runBlocking`.
 */
fun main(): Unit = Emulator.local(robots = 2, world = "push").use { emulator ->
    val report = emulator.runSimulated(limit = 120.seconds) {
        val fleet = Fleet(this)
        try {
            cooperativePush(fleet, emulator.discoverer(), log = ::println)
        } finally {
            fleet.disconnect()
        }
    }
    println("robots ${report.first} and ${report.second}: pushes started at robot times ${report.pushStartMs}")
    println("box cleared: ${"%.0f".format(emulator.boxClearanceM() * 1000)} mm off the tape in ${"%.1f".format(report.clearedAtMs / 1000.0)} s")
}

/** How the push went: the robot that found the box first, its helper, the robot time of each push's start, when the push ended. */
class PushReport(
    val first: Int,
    val second: Int,
    /** Push movement id per robot id: the firmware starts it in the tick it reports it as its current movement. */
    val pushIds: Map<Int, Int>,
    val pushStartMs: Map<Int, Long>,
    /** Robot time (ms since its reset) when both pushes had ended. */
    val clearedAtMs: Long,
)

private const val FOLLOW_MPS = 0.10
private const val CREEP_MPS = 0.04
private const val TURN_MPS = 0.05
private const val PUSH_MPS = 0.08
/**
 * Each robot pushes one half of the 140 mm box, its axle this far beside the line: the bodies (32 mm wide) 40 mm
 * apart and 18 mm inside the box's ends. A turn on the spot ends a degree or two off (one encoder pulse of one wheel
 * is 1.6 degrees of heading), which over the 0.3 m the two drive side by side is up to about 15 mm sideways.
 */
private const val SIDE_M = 0.036
/** The push: up to the box (about 60 mm) and about 160 mm on, enough to move the box out of the loop's corner. */
private const val PUSH_M = 0.22

/**
 * The host's part of the scenario, with the SDK's public API only: connects two robots from [discoverer] into
 * [fleet], runs the scenario and returns when both follow the line again (after [followAfter]), stopped.
 */
suspend fun cooperativePush(
    fleet: Fleet,
    discoverer: Discoverer,
    followAfter: kotlin.time.Duration = 6.seconds,
    log: (String) -> Unit = {},
): PushReport = coroutineScope {
    val robots = fleet.discoverAndConnect(discoverer, count = 2)
    check(robots.size == 2) { "found ${robots.size} robot(s), the scenario needs 2" }
    // States every 30 ms: the host reacts to what the IR sees within a few centimetres at line following speed.
    robots.map { async { it.reflector.set(SyncMode.FULL, 30.milliseconds) } }.awaitAll()
    log("both robots follow the line at $FOLLOW_MPS m/s")
    robots.map { async { it.lineFollower.start(FOLLOW_MPS) } }.awaitAll()

    // The first to see the box stops and waits for help.
    val watchers = robots.map { r -> async { r.state.first { it.proximity.front.seesObstacle }; r } }
    val first = select { watchers.forEach { w -> w.onAwait { it } } }
    watchers.forEach { it.cancel() }
    first.locomotion.stop(immediate = true)
    val second = robots.single { it !== first }
    log("${first.identity.name} sees the box and waits for help")
    // The second stops when it hears the first close ahead (or sees the box itself).
    second.state.first { s ->
        s.proximity.front.seesObstacle || s.proximity.front.isClose(first)
    }
    second.locomotion.stop(immediate = true)
    log("${second.identity.name} stops behind it")
    settle(first, second)
    // Both stand on the line and point along it: odometry heading 0 is the line's direction from here on, so that
    // turns on the spot can be squared up with it.
    for (r in robots) r.odometry.reset()

    // Side by side in front of the box: the first to the left half, the second to the right half.
    listOf(
        async { sidestep(first, SIDE_M, left = true) },
        async { sidestep(second, SIDE_M, left = false) },
    ).awaitAll()
    // Both creep up until they see the box: side by side at the same distance from it.
    listOf(async { creepUntilObstacle(first) }, async { creepUntilObstacle(second) }).awaitAll()
    settle(first, second)
    log("side by side at the box: pushing together")

    val pushes = fleet.enqueueTogether(mapOf(first to Movement.Straight(PUSH_M, PUSH_MPS), second to Movement.Straight(PUSH_M, PUSH_MPS)))
    val starts = HashMap<Int, Long>()
    val watch = pushes.map { (robot, handle) ->
        launch { robot.state.first { it.locomotion.currentId == handle.id }.also { starts[robot.identity.robotId] = it.time.timeMs } }
    }
    // The push ends when the first of the two ends: alone, the other could not move the box and would stall.
    val ends = pushes.values.map { h -> async { h.await() } }
    select { ends.forEach { e -> e.onAwait { it } } }
    fleet.stopAll(immediate = true)
    val results = pushes.mapValues { it.value.await() }
    watch.forEach { it.cancel() }
    check(results.values.any { it.outcome == MovementOutcome.FINISHED }) { "the push did not finish: $results" }
    val clearedAt = first.state.value.time.timeMs
    log("pushed ${results.values.map { "%.3f m".format(it.done) }}")
    settle(first, second)

    // Back off (the second further, so that the two can turn on the spot), and back onto the line one by one.
    listOf(
        async { first.locomotion.enqueue(Movement.Straight(-(results.getValue(first).done ?: PUSH_M), PUSH_MPS)).await() },
        async { second.locomotion.enqueue(Movement.Straight(-(results.getValue(second).done ?: PUSH_M) - 0.12, PUSH_MPS)).await() },
    ).awaitAll()
    settle(first, second)
    sidestep(first, SIDE_M, left = false)
    first.lineFollower.start(FOLLOW_MPS)
    sidestep(second, SIDE_M, left = true)
    log("back on the line: ${first.identity.name} leads, ${second.identity.name} keeps its distance")
    val keeper = launch { keepDistance(second, ahead = first) }
    delay(followAfter)
    keeper.cancel()
    fleet.stopAll(immediate = true)
    PushReport(first.identity.robotId, second.identity.robotId, pushes.entries.associate { (r, h) -> r.identity.robotId to h.id }, starts, clearedAt)
}

/** Whether this receiver hears [other] close by: at the mid distance class or nearer. */
private fun RobotState.ProximitySide.isClose(other: Robot): Boolean =
    hearsRobot && robotId == other.identity.robotId && distance >= DistanceClass.MID

/** Waits until the robots' wheels stand still, in a state the odometry has seen. */
private suspend fun settle(vararg robots: Robot) {
    for (r in robots) r.state.first { it.wheels.speedLeftMmps == 0 && it.wheels.speedRightMmps == 0 }
}

/**
 * Moves [robot] sideways by [distanceM]: a quarter turn, a straight, and a turn back to the line's direction (odometry
 * heading 0: what the first two movements really turned is taken back, not just a quarter turn). Each movement starts
 * at rest: the encoders have one channel and count the way a wheel is driven, so a wheel still rolling forward while
 * the next movement drives it back would count the wrong way.
 */
private suspend fun sidestep(robot: Robot, distanceM: Double, left: Boolean) {
    robot.locomotion.enqueue(Movement.Rotate(if (left) 90.0 else -90.0, TURN_MPS)).await()
    robot.locomotion.enqueue(Movement.Straight(distanceM, TURN_MPS))
    robot.locomotion.awaitSettled() // the odometry of a state after the movements
    robot.locomotion.enqueue(Movement.Rotate(-robot.odometry.pose.value.headingDeg, TURN_MPS)).await()
}

/** Drives [robot] slowly ahead until its front IR sees an obstacle (backing off first if it sees one already). */
private suspend fun creepUntilObstacle(robot: Robot) {
    if (robot.proximity.obstacleFront) {
        robot.locomotion.enqueue(Movement.Straight(-0.04, CREEP_MPS)).await()
        val at = robot.state.value.time.timeMs
        robot.state.first { it.time.timeMs > at + 300 } // the sighting fades after proximity.hold_ms
    }
    val creep = robot.locomotion.enqueue(Movement.Straight(0.3, CREEP_MPS))
    robot.state.first { it.proximity.front.seesObstacle || creep.isDone }
    robot.locomotion.stop(immediate = true)
}

/** Line following behind [ahead]: waits while it is close in front, follows at full speed once it is away. */
private suspend fun keepDistance(robot: Robot, ahead: Robot) {
    var waiting = true
    robot.state.collect { s ->
        val close = s.proximity.front.isClose(ahead)
        if (close && !waiting) robot.lineFollower.stop()
        if (!close && waiting) robot.lineFollower.start(FOLLOW_MPS)
        waiting = close
    }
}

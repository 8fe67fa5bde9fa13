package org.pocketbot.examples

import kotlinx.coroutines.delay
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.sdk.DistanceClass
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.hearsRobot
import kotlin.time.Duration.Companion.seconds
import kotlin.time.TimeSource

/**
 * Multiple robots on a track (thesis A.3), steered from the host: three robots follow the round track at different
 * speeds; when one sees another close ahead (IR proximity, front receiver) the host slows it down to keep its
 * distance, and lets it speed up again once the way is clear. A line per robot shows the live state every second.
 *
 * `make run` runs it against an embedded emulator in real time until Ctrl-C; `--seconds N` stops after N seconds.
 */
fun main(args: Array<String>): Unit = runBlocking {
    val seconds = args.indexOf("--seconds").takeIf { it >= 0 }?.let { args[it + 1].toInt() }
    val cruise = listOf(0.10, 0.16, 0.22) // m/s: the faster robots catch up with the slower ones
    val yielding = 0.05

    Emulator.local(robots = cruise.size, world = "round").use { emulator ->
        emulator.start(Speed.Realtime(1.0))
        val fleet = Fleet(this)
        val robots = fleet.discoverAndConnect(emulator.discoverer(), count = cruise.size)
        println("connected: " + robots.joinToString { "${it.identity.name} (id ${it.identity.robotId})" })

        val speedOf = robots.withIndex().associate { (i, r) -> r to cruise[i] }.toMutableMap()
        val drivers = robots.map { robot ->
            robot.odometry.reset(emulator.robot(robot.identity.robotId).truePose)
            robot.lineFollower.start(speedMps = speedOf.getValue(robot))
            launch { keepDistance(robot, speedOf.getValue(robot), yielding) { speedOf[robot] = it } }
        }

        val clock = TimeSource.Monotonic.markNow()
        while (seconds == null || clock.elapsedNow() < seconds.seconds) {
            delay(1.seconds)
            println("t=${clock.elapsedNow().inWholeSeconds}s")
            for (robot in robots) println("  " + statusLine(robot, emulator, speedOf.getValue(robot)))
        }
        drivers.forEach { it.cancel() }
        fleet.stopAll()
        for (robot in robots) println("${robot.identity.name}: link ${robot.linkStats.value}")
        fleet.close()
        emulator.stop()
    }
}

/**
 * Slows [robot] to [yielding] while another robot is close in front, back to [cruise] once none was seen close for
 * [clearAfterMs] of robot time (the distance class flickers as the other robot's beacons cycle their power).
 */
private suspend fun keepDistance(robot: Robot, cruise: Double, yielding: Double, report: (Double) -> Unit) {
    val clearAfterMs = 1500L
    var slowed = false
    var lastCloseMs = 0L
    robot.state.collect { state ->
        val ahead = state.proximity.front
        val close = ahead.hearsRobot &&
            ahead.distance.let { it == DistanceClass.NEAR || it == DistanceClass.MID }
        if (close) lastCloseMs = state.time.timeMs
        val slow = close || (slowed && state.time.timeMs - lastCloseMs < clearAfterMs)
        if (slow != slowed) {
            slowed = slow
            val speed = if (slow) yielding else cruise
            robot.lineFollower.start(speedMps = speed)
            report(speed)
            val why = if (slow) "robot ${ahead.robotId} close ahead, slowing" else "way clear, cruising"
            println("${robot.identity.name}: $why at ${"%.2f".format(speed)} m/s")
        }
    }
}

private fun statusLine(robot: Robot, emulator: Emulator, speedMps: Double): String {
    val s = robot.state.value
    val truth = emulator.robot(robot.identity.robotId).truePose
    val odo = robot.odometry.pose.value
    val errMm = odo.distanceTo(truth) * 1000
    return "%-12s set %.2f m/s  wheels %4d/%4d mm/s  line %5d  %-9s  odometry (%.3f, %.3f) m, off truth %.1f mm  battery %d mV".format(
        robot.identity.name, speedMps, s.wheels.speedLeftMmps, s.wheels.speedRightMmps, s.line.position,
        robot.lineFollower.followStatus?.name?.lowercase() ?: "?", odo.xM, odo.yM, errMm, s.power.batteryMv,
    )
}

package org.pocketbot.examples

import kotlinx.coroutines.async
import kotlinx.coroutines.awaitAll
import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.EmulatorConfig
import org.pocketbot.emulator.runSimulated
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.transport.Discoverer
import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds

/**
 * Multiple robots on a track (thesis A.3), decentralized: three robots on the round track with a box on it. The
 * behaviour runs in each robot's firmware (the SDK's [org.pocketbot.sdk.TrackBehaviour]): the robots follow the line,
 * keep their distance, greet each other when they meet, hand a token on from robot to robot (the holder shows it
 * with its token LED, the thesis's orange light) and drive round the box. The host only starts them, reverses their
 * direction halfway and prints what it sees every 10 s.
 *
 * `make track` runs it for 120 s on the emulator's `track` world on simulated time (repeatable, a few seconds); its
 * last line is `token visits: <id>=<n> <id>=<n> <id>=<n> in <s> s`, the visits as the robots count them.
 * `make track ARGS="--seconds 60"` runs it for another time; `--seed N` seeds the emulator's random effects (sensor
 * noise, encoder phases; default 1, as every emulator), so `make track ARGS="--seed 6"` replays another run.
 */
fun main(args: Array<String>) {
    val seconds = args.indexOf("--seconds").takeIf { it >= 0 }?.let { args[it + 1].toDouble() } ?: 120.0
    val seed = args.indexOf("--seed").takeIf { it >= 0 }?.let { args[it + 1].toLong() } ?: EmulatorConfig().seed
    Emulator.local(robots = 3, world = "track", config = EmulatorConfig(seed = seed)).use { emulator ->
        val report = emulator.runSimulated(limit = (seconds + 60).seconds) {
            val fleet = Fleet(this)
            try {
                runTrack(fleet, emulator.discoverer(), seconds.seconds, log = ::println)
            } finally {
                fleet.disconnect()
            }
        }
        println("token visits: ${report.visits.entries.joinToString(" ") { (id, n) -> "$id=$n" }} in ${"%.1f".format(report.seconds)} s")
    }
}

/** What the robots reported at the end: token visits by robot id, in id order, and how long the behaviour ran. */
class TrackReport(val visits: Map<Int, Int>, val seconds: Double)

/**
 * The host's part, with the SDK's public API only: connects three robots from [discoverer] into [fleet], starts the
 * track behaviour on each, reverses them all after half of [duration], stops them after [duration] (robot time)
 * and returns the token visits each robot counted.
 */
suspend fun runTrack(fleet: Fleet, discoverer: Discoverer, duration: Duration, log: (String) -> Unit = {}): TrackReport = coroutineScope {
    val robots = fleet.discoverAndConnect(discoverer, count = 3).sortedBy { it.identity.robotId }
    check(robots.size == 3) { "found ${robots.size} robot(s), the scenario needs 3" }
    robots.map { async { it.track.start() } }.awaitAll()
    log("started the track behaviour on ${robots.joinToString { it.identity.name }}")
    var reversed = false
    var elapsed = Duration.ZERO
    while (elapsed < duration) {
        val step = minOf(10.seconds, duration - elapsed)
        delay(step)
        elapsed += step
        log("t=${elapsed.inWholeSeconds} s  " + robots.joinToString("  ") { status(it) })
        if (!reversed && elapsed >= duration / 2) {
            robots.map { async { it.track.reverse() } }.awaitAll()
            reversed = true
            log("reversed: the robots turn round and go the other way")
        }
    }
    robots.map { async { it.track.stop() } }.awaitAll()
    // The visits of a state sent after the stop.
    val stoppedAt = robots.map { it.state.value.time.timeMs }
    robots.zip(stoppedAt).forEach { (r, t) -> r.state.first { it.time.timeMs > t } }
    TrackReport(robots.associate { it.identity.robotId to it.track.tokenVisits }, duration.inWholeMilliseconds / 1000.0)
}

private fun status(robot: Robot): String {
    val t = robot.track
    val token = if (t.holdsToken) " TOKEN" else ""
    return "${robot.identity.robotId}: ${t.status.name.lowercase()}, visits ${t.tokenVisits}, met ${t.metId}$token"
}

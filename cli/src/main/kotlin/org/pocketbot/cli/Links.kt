package org.pocketbot.cli

import kotlinx.coroutines.ExperimentalCoroutinesApi
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.channelFlow
import kotlinx.coroutines.flow.collectLatest
import kotlinx.coroutines.flow.distinctUntilChanged
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.map
import kotlinx.coroutines.launch
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Robot
import kotlin.time.Duration.Companion.seconds

/**
 * How long a command waits for a robot's lost link to come back before it gives up (exit 5). Longer than the robot's
 * default link failsafe (1 s): when the link returns within it, a movement the failsafe cut is reported as such.
 */
val LINK_GRACE = 3.seconds

/** Where a robot's link stands, as far as a command cares. */
private enum class Reach { UP, DOWN, CLOSED }

/**
 * Suspends until one of [robots] had its link down for [LINK_GRACE] without a break (the SDK tries again and again
 * meanwhile), or closed, and returns the exception that says which robot and why.
 */
@OptIn(ExperimentalCoroutinesApi::class)
suspend fun linkGone(robots: List<Robot>): LinkLostException = channelFlow {
    for (r in robots) launch {
        var lostBecause: String? = null
        r.connection.map { c ->
            if (c is ConnectionState.Lost && lostBecause == null) lostBecause = c.reason
            when (c) {
                ConnectionState.Connected, ConnectionState.Connecting -> Reach.UP.also { lostBecause = null }
                is ConnectionState.Closed -> Reach.CLOSED
                else -> Reach.DOWN
            }
        }.distinctUntilChanged().collectLatest { reach ->
            if (reach == Reach.UP) return@collectLatest
            if (reach == Reach.DOWN) delay(LINK_GRACE)
            val now = r.connection.value
            val why = lostBecause ?: describe(now)
            val latest = (now as? ConnectionState.Lost)?.reason?.takeIf { it != why }
            send(LinkLostException(
                "lost the link to ${r.label}: $why" +
                    if (reach == Reach.DOWN) "; it did not come back within ${LINK_GRACE.inWholeSeconds} s" + (latest?.let { " ($it)" } ?: "") else "",
            ))
        }
    }
}.first()

/** Where a link stands, in words. */
fun describe(c: ConnectionState): String = when (c) {
    ConnectionState.Connecting -> "connecting"
    ConnectionState.Connected -> "connected"
    is ConnectionState.Lost -> "link lost: ${c.reason}"
    is ConnectionState.Reconnecting -> "reconnecting (attempt ${c.attempt})"
    is ConnectionState.Closed -> "closed" + (c.cause?.message?.let { ": $it" } ?: "")
}

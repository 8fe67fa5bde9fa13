package org.pocketbot.sdk.internal.link

import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.Job
import kotlin.time.Duration
import org.pocketbot.sdk.transport.Transport

/** One opened transport and everything that lives exactly as long as it: the read, heartbeat and drop counters. */
internal class Session(val transport: Transport) {
    // What happened since the heartbeat loop last woke: it keeps time by its own delays, so it follows the
    // dispatcher's clock (virtual time in simulations) and costs a few wake-ups a second, not one per frame.
    var received = false
    var sent = false
    var quiet: Duration = Duration.ZERO

    /** Completes with the reason once the session is over. */
    val ended = CompletableDeferred<String>()
    val jobs = ArrayList<Job>()

    val isLive: Boolean get() = !ended.isCompleted
}

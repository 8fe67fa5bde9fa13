package org.pocketbot.sdk.internal.link

import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.Job
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.SettingsData
import org.pocketbot.sdk.DebugLog
import org.pocketbot.sdk.RobotOptions

/**
 * What the robot's modules (settings, locomotion, line follower, proximity, reflector, odometry) may do with the
 * link: send commands on its two lanes, send unacknowledged packets, and run work on its serial context. Sessions,
 * the handshake, supervision, reconnects, heartbeats and sequence numbers stay behind it in [Link].
 */
internal interface LinkPort {
    /** The options the robot was connected with. */
    val options: RobotOptions

    /** Where the SDK's warnings about this robot go. */
    val debugLog: DebugLog

    /**
     * Sends an acknowledged command and suspends until the robot acknowledged it. Commands go out one at a time in
     * call order; a loss waits for the reconnect, which sends the command again unless the robot already holds it.
     * [wanted] is asked before every transmission: once it says no, the command is withdrawn
     * ([CommandWithdrawnException]). [beforeFirstSend], when given, is awaited once the link is ready to send.
     *
     * @throws org.pocketbot.sdk.CommandRefusedException when the robot answers with `error`.
     */
    suspend fun command(packet: Packet, wanted: () -> Boolean = ALWAYS_WANTED, beforeFirstSend: (suspend () -> Unit)? = null)

    /** Sends an acknowledged command ahead of everything: at once, or first after the reconnect. */
    suspend fun urgent(packet: Packet)

    /** Sends an unacknowledged packet if the link is up; false when it is not. */
    suspend fun sendUnacked(packet: Packet): Boolean

    /** Runs [block] on the link's serial context, where every module's state is touched. */
    suspend fun <T> serial(block: suspend () -> T): T

    /** Starts [block] among the robot's own coroutines (it ends when the robot closes). */
    fun launch(block: suspend () -> Unit): Job

    /** Suspends until [deferred] completes or the robot closes. */
    suspend fun <T> awaitOrClosed(deferred: CompletableDeferred<T>): T

    /** Receives `settings_data` chunks while a settings read runs; returns false for a chunk it did not expect. */
    var settingsSink: ((SettingsData) -> Boolean)?
}

/** The default of [LinkPort.command]'s `wanted`: one shared instance instead of a lambda per command. */
internal val ALWAYS_WANTED: () -> Boolean = { true }

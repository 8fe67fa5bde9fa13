package org.pocketbot.sdk.mqtt

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.StateFlow
import org.pocketbot.sdk.transport.Discoverer

/**
 * Serves the robots this host reaches (Bluetooth, serial, TCP, an emulator) to a broker, so that fleet clients on
 * other hosts drive them: each client session gets a link of its own to the robot, its frames pass unchanged. Made
 * by [startGateway]; a child of the scope it was started in.
 */
public class Gateway internal constructor() {
    /** The gateway's name: the first level of its topics, `pb/v1/<name>/...`. */
    public val name: String get() = TODO()

    /** The ids of the robots served, in the order they were found. */
    public val robots: StateFlow<List<String>> get() = TODO()

    /** Counters since the start: sessions, frames and messages, and what was dropped and why. */
    public val stats: StateFlow<GatewayStats> get() = TODO()

    /** Closes every session, removes the robots' announcements, says offline and disconnects; idempotent. */
    public suspend fun close() {
        TODO()
    }
}

/**
 * Starts a gateway named [name] (letters, digits, `-` and `_`) on the broker of [options], serving every robot
 * [devices] finds (an emulator's discoverer, a [org.pocketbot.sdk.transport.Discoverer] of serial ports...). A
 * robot's id is its device name made topic-safe; a name seen twice gets `-2`, `-3`... Throws [BrokerException] when
 * the first connect fails.
 */
public suspend fun CoroutineScope.startGateway(name: String, options: BrokerOptions, devices: Discoverer): Gateway =
    TODO("$name $options $devices")

/**
 * A gateway's counters since it started.
 *
 * @property sessions sessions opened.
 * @property framesUp frames sent up from robots to clients.
 * @property messagesUp up messages published (several frames share one while state streams).
 * @property framesDown frames passed down to robots.
 * @property droppedGarbage down messages that could not be read.
 * @property droppedOversize down messages over 16 KiB, or holding a frame over the protocol's largest.
 * @property droppedUnknownRobot messages on a topic naming no robot served, or of the wrong shape.
 * @property droppedLate down messages older than [BrokerOptions.maxFrameAge] on arrival.
 * @property droppedNotAllowed frames a watching session may not send (anything that moves or changes the robot).
 */
public class GatewayStats(
    public val sessions: Int,
    public val framesUp: Long,
    public val messagesUp: Long,
    public val framesDown: Long,
    public val droppedGarbage: Long,
    public val droppedOversize: Long,
    public val droppedUnknownRobot: Long,
    public val droppedLate: Long,
    public val droppedNotAllowed: Long,
) {
    /** Every message or frame dropped, whatever the reason. */
    public val dropped: Long get() = droppedGarbage + droppedOversize + droppedUnknownRobot + droppedLate + droppedNotAllowed

    private fun values() = listOf(sessions.toLong(), framesUp, messagesUp, framesDown, droppedGarbage, droppedOversize,
        droppedUnknownRobot, droppedLate, droppedNotAllowed)

    override fun equals(other: Any?): Boolean = other is GatewayStats && values() == other.values()
    override fun hashCode(): Int = values().hashCode()
    override fun toString(): String =
        "GatewayStats(sessions=$sessions, framesUp=$framesUp, messagesUp=$messagesUp, framesDown=$framesDown, " +
            "droppedGarbage=$droppedGarbage, droppedOversize=$droppedOversize, droppedUnknownRobot=$droppedUnknownRobot, " +
            "droppedLate=$droppedLate, droppedNotAllowed=$droppedNotAllowed)"
}

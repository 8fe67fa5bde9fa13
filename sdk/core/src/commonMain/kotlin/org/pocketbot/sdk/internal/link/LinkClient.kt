package org.pocketbot.sdk.internal.link

import org.pocketbot.protocol.Driver
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.Packet
import kotlin.time.Duration

/**
 * What the link hands to the robot's modules and asks of them. Every call happens on the link's serial context.
 * The link knows frames, sessions and commands; the client knows what the packets mean.
 */
internal interface LinkClient {
    /** A packet the link itself does not consume: state, debug text, IR messages, movement reports. */
    fun onPacket(packet: Packet)

    /**
     * After the handshake of every session (and after a robot reset), before ordinary commands flow again: bring
     * the robot and the host's mirror in line (settings, movement handles, sync mode). [driver] is the robot's
     * answer to this host's role (who drives, the robot's time). [exchange] runs one acknowledged command on this
     * session and throws when it is refused, times out or the session ends.
     */
    suspend fun restore(hello: Hello, firstSession: Boolean, driver: Driver, exchange: suspend (Packet) -> Unit)

    /** A frame from the robot was lost on the way (and counted in the link stats): a report it carried is missing. */
    fun onFrameDropped()

    /** True when the robot already holds what [packet] asks for (a movement seen in its log or queue). */
    fun alreadyHeld(packet: Packet): Boolean

    /** How long the link may stay silent before it counts as lost; null while no state is expected. */
    val silenceTimeout: Duration?

    /** The longest quiet time before a heartbeat. */
    val heartbeatPeriod: Duration
}

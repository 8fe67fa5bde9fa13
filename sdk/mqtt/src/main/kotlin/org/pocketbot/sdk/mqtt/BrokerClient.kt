package org.pocketbot.sdk.mqtt

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.StateFlow
import org.pocketbot.sdk.transport.Discoverer

/**
 * A program's connection to a broker, through which it reaches the robots of every gateway serving to it. One MQTT
 * connection, shared by every robot opened through it; when the broker goes away the client reconnects by itself
 * ([connected] says when it is up) and the robots' links end with a
 * [org.pocketbot.sdk.transport.TransportLostException], so each [org.pocketbot.sdk.Robot] reconnects as it would to
 * a robot on any other link. Made by [connectBroker]; a child of the scope it was made in.
 *
 * ```
 * val broker = connectBroker(BrokerOptions("mqtts://broker.lab") { username = "alice"; password = secret })
 * val robots = broker.discoverer().discover().toList().map { it.connect(this) }
 * ```
 */
public class BrokerClient internal constructor() {
    /** The options this client connected with. */
    public val options: BrokerOptions get() = TODO()

    /** True while the MQTT session with the broker is up; it reconnects by itself after a loss. */
    public val connected: StateFlow<Boolean> get() = TODO()

    /** Every gateway the broker knows of, by name, from its retained status: online or gone. */
    public val gateways: StateFlow<Map<String, GatewayPresence>> get() = TODO()

    /**
     * Finds the robots every gateway announces: each becomes a [BrokerRobotDevice]. The search completes after a
     * short settle (1 s without a new robot), like the emulator's.
     */
    public fun discoverer(): Discoverer = TODO()

    /** The robot [robot] of gateway [gateway], announced or not yet (opening it fails until it is). */
    public fun device(gateway: String, robot: String): BrokerRobotDevice = TODO("$gateway $robot")

    /** Ends every robot's link and disconnects; idempotent. */
    public suspend fun close() {
        TODO()
    }
}

/**
 * Connects to the broker of [options]: the connection is a child of this scope and ends with it or with
 * [BrokerClient.close]. Throws [BrokerException] saying why when the first connect fails (refused: not authorised,
 * bad username or password, broker unreachable, TLS failed); later losses show in [BrokerClient.connected].
 */
public suspend fun CoroutineScope.connectBroker(options: BrokerOptions): BrokerClient = TODO("$options")

/** Connecting to a broker failed: [message] says why (unreachable, refused credentials, not authorised, TLS). */
public class BrokerException(message: String, cause: Throwable? = null) : Exception(message, cause)

/**
 * What a gateway's retained status says.
 *
 * @property online true while the gateway is connected; false once it closed or its connection was lost (its last
 *   will).
 * @property robots how many robots it serves (0 when offline).
 * @property since when this client learned the status, in milliseconds since the epoch; null before it did.
 */
public class GatewayPresence(public val online: Boolean, public val robots: Int, public val since: Long?) {
    override fun equals(other: Any?): Boolean =
        other is GatewayPresence && online == other.online && robots == other.robots && since == other.since
    override fun hashCode(): Int = (online.hashCode() * 31 + robots) * 31 + since.hashCode()
    override fun toString(): String = "GatewayPresence(online=$online, robots=$robots, since=$since)"
}

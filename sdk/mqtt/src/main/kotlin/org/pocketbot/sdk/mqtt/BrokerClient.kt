package org.pocketbot.sdk.mqtt

import com.hivemq.client.mqtt.mqtt5.message.publish.Mqtt5Publish
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.channelFlow
import kotlinx.coroutines.flow.combine
import kotlinx.coroutines.flow.filterNotNull
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.withTimeoutOrNull
import kotlinx.serialization.json.Json
import kotlinx.serialization.json.JsonObject
import kotlinx.serialization.json.booleanOrNull
import kotlinx.serialization.json.contentOrNull
import kotlinx.serialization.json.intOrNull
import kotlinx.serialization.json.JsonPrimitive
import org.pocketbot.sdk.mqtt.internal.MqttLink
import org.pocketbot.sdk.mqtt.internal.Topics
import org.pocketbot.sdk.mqtt.internal.Wire
import org.pocketbot.sdk.mqtt.internal.randomHex
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.TransportLostException
import java.util.concurrent.ConcurrentHashMap
import kotlin.time.Duration.Companion.seconds

/**
 * A program's connection to a broker, through which it reaches the robots of every gateway serving to it. One MQTT
 * connection, shared by every robot opened through it; when the broker goes away the client reconnects by itself
 * ([connected] says when it is up) and the robots' links end with a [TransportLostException], so each
 * [org.pocketbot.sdk.Robot] reconnects as it would to a robot on any other link. Made by [connectBroker]; a child of
 * the scope it was made in: cancelling the scope closes it, and the scope does not complete while it is open.
 *
 * ```
 * val broker = connectBroker(BrokerOptions("mqtts://broker.lab") { username = "alice"; password = secret })
 * val robots = broker.discoverer().discover().toList().map { it.connect(this) }
 * ```
 */
public class BrokerClient internal constructor(
    /** The options this client connected with. */
    public val options: BrokerOptions,
    scope: CoroutineScope,
) {
    private val job = SupervisorJob(scope.coroutineContext[Job])
    internal val user: String = options.username ?: "anonymous"
    internal val clientId: String = options.clientId ?: "pb-${randomHex(8)}"
    private val _gateways = MutableStateFlow<Map<String, GatewayPresence>>(emptyMap())
    private val robotInfos = MutableStateFlow<Map<Pair<String, String>, RobotInfo>>(emptyMap())
    private val transports = ConcurrentHashMap<String, BrokerTransport>()  // by session id
    private val _leases = MutableStateFlow<Map<Pair<String, String>, String?>>(emptyMap())

    /** Who drives each robot (the MQTT user of the driving session, from the gateways' retained leases). */
    internal val leases: StateFlow<Map<Pair<String, String>, String?>> = _leases.asStateFlow()

    internal val link = MqttLink(
        options, clientId,
        willTopic = Topics.client(user, clientId), willPayload = OFFLINE, willRetain = false,
        onConnected = {},
        onDisconnected = { reason -> loseAll("the broker connection was lost: $reason") },
        onMessage = ::received,
    )

    /** True while the MQTT session with the broker is up; it reconnects by itself after a loss. */
    public val connected: StateFlow<Boolean> get() = link.connected

    /** Every gateway the broker knows of, by name, from its retained status: online or gone. */
    public val gateways: StateFlow<Map<String, GatewayPresence>> = _gateways.asStateFlow()

    init {
        check(job.isActive) { "cannot connect to a broker: the scope has ended" }
        job.invokeOnCompletion { link.client.disconnect() }
    }

    /**
     * Finds the robots every online gateway announces: each becomes a [BrokerRobotDevice]. The search completes
     * after a short settle (1 s without a new robot), like the emulator's.
     */
    public fun discoverer(): Discoverer = object : Discoverer {
        override fun discover(): Flow<RobotDevice> = channelFlow {
            val seen = HashSet<Pair<String, String>>()
            while (true) {
                val found = withTimeoutOrNull(DISCOVERY_SETTLE) {
                    combine(robotInfos, _gateways) { robots, gateways ->
                        robots.keys.firstOrNull { it !in seen && gateways[it.first]?.online == true }
                    }.filterNotNull().first()
                } ?: break
                seen += found
                send(device(found.first, found.second))
            }
        }

        override fun toString(): String = "BrokerDiscoverer(${options.url})"
    }

    /** The robot [robot] of gateway [gateway], announced or not yet (opening it fails until it is). */
    public fun device(gateway: String, robot: String): BrokerRobotDevice {
        require(Topics.isSafe(gateway) && Topics.isSafe(robot)) { "\"$gateway/$robot\" is not a gateway and robot id" }
        return BrokerRobotDevice(this, gateway, robot)
    }

    /** Ends every robot's link and disconnects; idempotent. */
    public suspend fun close() {
        for (t in transports.values.toList()) t.close()
        link.disconnect()
        job.cancel()
    }

    // ---- for BrokerRobotDevice -------------------------------------------------------------------------------------

    internal fun robotName(gateway: String, robot: String): String? = robotInfos.value[gateway to robot]?.name

    internal fun gatewayOnline(gateway: String): Boolean = _gateways.value[gateway]?.online == true

    internal fun robotAnnounced(gateway: String, robot: String): Boolean = (gateway to robot) in robotInfos.value

    internal fun register(t: BrokerTransport) { transports[t.session] = t }

    internal fun unregister(t: BrokerTransport) { transports.remove(t.session, t) }

    // ---- messages ---------------------------------------------------------------------------------------------------

    /** Every message the broker delivers; on the MQTT client's thread, so nothing here blocks. */
    private fun received(publish: Mqtt5Publish) {
        val levels = Topics.levels(publish.topic.toString()) ?: return
        val payload = publish.payloadAsBytes
        when {
            levels.size == 2 && levels[1] == "status" -> status(levels[0], payload)
            levels.size == 3 && levels[2] == "info" -> info(levels[0], levels[1], payload)
            levels.size == 3 && levels[2] == "lease" -> {
                val driver = (parse(payload)?.get("driver") as? JsonPrimitive)?.contentOrNull
                _leases.update { it + ((levels[0] to levels[1]) to driver) }
            }
            levels.size == 5 && levels[2] == Topics.UP && levels[3] == user -> transports[levels[4]]?.let { t ->
                if (t.gateway == levels[0] && t.robot == levels[1]) t.received(payload)
            }
        }
    }

    private fun status(gateway: String, payload: ByteArray) {
        val json = parse(payload)
        val online = (json?.get("online") as? JsonPrimitive)?.booleanOrNull ?: false
        val robots = (json?.get("robots") as? JsonPrimitive)?.intOrNull ?: 0
        _gateways.update { it + (gateway to GatewayPresence(online, if (online) robots else 0, System.currentTimeMillis())) }
        if (!online) loseWhere("gateway $gateway went offline") { it.gateway == gateway }
    }

    private fun info(gateway: String, robot: String, payload: ByteArray) {
        val json = if (payload.isEmpty()) null else parse(payload)
        if (json == null) {
            robotInfos.update { it - (gateway to robot) }
            loseWhere("gateway $gateway no longer serves $robot") { it.gateway == gateway && it.robot == robot }
        } else {
            val name = (json["name"] as? JsonPrimitive)?.contentOrNull ?: "$gateway/$robot"
            robotInfos.update { it + ((gateway to robot) to RobotInfo(name)) }
        }
    }

    private fun loseAll(reason: String) = loseWhere(reason) { true }

    private fun loseWhere(reason: String, which: (BrokerTransport) -> Boolean) {
        for (t in transports.values.toList()) if (which(t)) t.lost(reason)
    }

    private class RobotInfo(val name: String)

    internal companion object {
        val OFFLINE: ByteArray = "offline".encodeToByteArray()
        val DISCOVERY_SETTLE = 1.seconds

        fun parse(payload: ByteArray): JsonObject? = try {
            Json.parseToJsonElement(payload.decodeToString()) as? JsonObject
        } catch (e: Exception) {
            null
        }

        val UP_KINDS = setOf(Wire.FRAMES, Wire.CLOSED)
    }
}

/**
 * Connects to the broker of [options]: the connection is a child of this scope and ends with it or with
 * [BrokerClient.close]. Throws [BrokerException] saying why when the first connect fails (refused: not authorised,
 * bad username or password, broker unreachable, TLS failed); later losses show in [BrokerClient.connected].
 */
public suspend fun CoroutineScope.connectBroker(options: BrokerOptions): BrokerClient {
    val client = BrokerClient(options, this)
    try {
        client.link.connect()
        client.link.subscribe(listOf(
            "${Topics.PREFIX}/+/status",
            "${Topics.PREFIX}/+/+/info",
            "${Topics.PREFIX}/+/+/lease",
            "${Topics.PREFIX}/+/+/up/${client.user}/#",
        ))
    } catch (e: Throwable) {
        client.close()
        throw e
    }
    return client
}

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

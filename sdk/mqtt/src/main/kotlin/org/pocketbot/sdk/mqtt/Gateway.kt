package org.pocketbot.sdk.mqtt

import com.hivemq.client.mqtt.datatypes.MqttQos
import com.hivemq.client.mqtt.mqtt5.message.publish.Mqtt5Publish
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.ExperimentalCoroutinesApi
import kotlinx.coroutines.Job
import kotlinx.coroutines.NonCancellable
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.delay
import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.channels.ChannelResult
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import kotlinx.coroutines.selects.onTimeout
import kotlinx.coroutines.selects.select
import kotlinx.coroutines.withContext
import kotlinx.coroutines.withTimeoutOrNull
import kotlinx.serialization.json.JsonNull
import kotlinx.serialization.json.JsonPrimitive
import kotlinx.serialization.json.buildJsonObject
import kotlinx.serialization.json.put
import org.pocketbot.protocol.DebugText
import org.pocketbot.protocol.Driver
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.HostRole
import org.pocketbot.protocol.PACKET_SPECS
import org.pocketbot.protocol.SetRole
import org.pocketbot.protocol.StateFull
import org.pocketbot.protocol.StateReduced
import org.pocketbot.sdk.mqtt.internal.MqttLink
import org.pocketbot.sdk.mqtt.internal.Topics
import org.pocketbot.sdk.mqtt.internal.Wire
import org.pocketbot.sdk.mqtt.internal.monotonicMs
import org.pocketbot.sdk.mqtt.internal.randomHex
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport
import java.util.concurrent.ConcurrentHashMap
import kotlin.time.Duration.Companion.seconds

/**
 * Serves the robots this host reaches (Bluetooth, serial, TCP, an emulator) to a broker, so that fleet clients on
 * other hosts drive them: each client session gets a link of its own to the robot ([RobotDevice.open]) and its
 * frames pass unchanged. The robot's own rule of one driver and many watchers is the lease, which the gateway
 * publishes. Made by [startGateway]; a child of the scope it was started in: cancelling the scope closes it, and
 * the scope does not complete while it is open.
 */
public class Gateway internal constructor(
    /** The gateway's name: the first level of its topics, `pb/v1/<name>/...`. */
    public val name: String,
    private val options: BrokerOptions,
    scope: CoroutineScope,
) {
    private val job = SupervisorJob(scope.coroutineContext[Job])
    private val scope = CoroutineScope(scope.coroutineContext + job + Dispatchers.Default)
    private val served = ConcurrentHashMap<String, Served>()
    private val sessions = ConcurrentHashMap<String, Session>()
    private val recentlyEnded = ConcurrentHashMap<String, Long>()  // session key -> when, so stragglers do not reopen it
    private val _robots = MutableStateFlow<List<String>>(emptyList())
    private val counters = Counters()
    @Volatile private var closing = false

    internal val link = MqttLink(
        options, options.clientId ?: "pb-gw-$name-${randomHex(4)}",
        willTopic = Topics.status(name), willPayload = OFFLINE_STATUS, willRetain = true,
        onConnected = { this.scope.launch { announce() } },
        onDisconnected = {},
        onMessage = ::received,
    )

    /** The ids of the robots served, in the order they were found. */
    public val robots: StateFlow<List<String>> = _robots.asStateFlow()

    /** Counters since the start: sessions, frames and messages, and what was dropped and why. */
    public val stats: StateFlow<GatewayStats> get() = counters.flow

    init {
        check(job.isActive) { "cannot start gateway $name: the scope has ended" }
        job.invokeOnCompletion { link.client.disconnect() }
    }

    /** Closes every session, removes the robots' announcements, says offline and disconnects; idempotent. */
    public suspend fun close() {
        if (closing) return
        closing = true
        withContext(NonCancellable) {
            for (s in sessions.values.toList()) s.end("the gateway closed")
            // A stalled broker does not hold the close up: its clients learn of it from the last will instead.
            if (link.connected.value) withTimeoutOrNull(CLOSE_TIMEOUT) {
                for (id in served.keys) {
                    link.publishAndWait(Topics.info(name, id), ByteArray(0), retain = true)
                    link.publishAndWait(Topics.lease(name, id), ByteArray(0), retain = true)
                }
                link.publishAndWait(Topics.status(name), OFFLINE_STATUS, retain = true)
            }
            link.disconnect()
        }
        job.cancel()
    }

    internal suspend fun start(devices: Discoverer) {
        link.connect()
        link.subscribe(listOf(
            "${Topics.PREFIX}/$name/+/${Topics.DOWN}/#",
            "${Topics.PREFIX}/$name/+/${Topics.WATCH}/#",
            "${Topics.PREFIX}/${Topics.CLIENTS}/#",
        ))
        scope.launch {
            try {
                devices.discover().collect { add(it) }
            } catch (e: Exception) {
                // A discoverer that fails serves what it found so far.
            }
        }
        scope.launch { forgetEndedSessions() }
    }

    // ---- robots and presence ----------------------------------------------------------------------------------------

    private class Served(val id: String, val device: RobotDevice) {
        @Volatile var lease: String? = null
    }

    private fun add(device: RobotDevice) {
        val base = Topics.safe(device.name)
        val robot = synchronized(served) {
            val id = generateSequence(1) { it + 1 }.map { if (it == 1) base else "$base-$it" }.first { !served.containsKey(it) }
            Served(id, device).also { served[id] = it }
        }
        _robots.update { it + robot.id }
        if (link.connected.value) {
            publishInfo(robot)
            publishLease(robot)
            publishStatus()
        }
    }

    /** Everything retained, again after each (re)connect: a restarted broker has forgotten it. */
    private fun announce() {
        for (robot in served.values) {
            publishInfo(robot)
            publishLease(robot)
        }
        publishStatus()
    }

    private fun publishStatus() {
        val json = buildJsonObject { put("online", true); put("robots", served.size); put("version", VERSION) }
        link.publish(Topics.status(name), json.toString().encodeToByteArray(), MqttQos.AT_LEAST_ONCE, retain = true)
    }

    private fun publishInfo(robot: Served) {
        val json = buildJsonObject { put("name", robot.device.name); put("link", robot.device.address) }
        link.publish(Topics.info(name, robot.id), json.toString().encodeToByteArray(), MqttQos.AT_LEAST_ONCE, retain = true)
    }

    private fun publishLease(robot: Served) {
        val json = buildJsonObject { put("driver", robot.lease?.let(::JsonPrimitive) ?: JsonNull) }
        link.publish(Topics.lease(name, robot.id), json.toString().encodeToByteArray(), MqttQos.AT_LEAST_ONCE, retain = true)
    }

    /** Who drives [robot] now: the user of the session whose link the robot says drives, else the host it names. */
    private fun updateLease(robot: Served, label: String) {
        val driver = sessions.values.firstOrNull { it.robot === robot && it.drives }?.user ?: label.ifEmpty { null }
        if (driver != robot.lease) {
            robot.lease = driver
            publishLease(robot)
        }
    }

    // ---- messages from the broker -----------------------------------------------------------------------------------

    /** Every message the broker delivers; on the MQTT client's thread, so nothing here blocks. */
    private fun received(publish: Mqtt5Publish) {
        val now = monotonicMs()
        val levels = Topics.levels(publish.topic.toString())
        if (levels != null && levels.size == 3 && levels[0] == Topics.CLIENTS) {
            clientGone(user = levels[1], clientId = levels[2])
            return
        }
        if (levels == null || levels.size != 5 || levels[0] != name || levels[2] !in SESSION_KINDS ||
            !Topics.isSafe(levels[3]) || !Topics.isSafe(levels[4])) {
            counters.add { droppedUnknownRobot++ }
            return
        }
        val robot = served[levels[1]] ?: return counters.add { droppedUnknownRobot++ }
        val payload = publish.payloadAsBytes
        if (payload.size > Wire.MAX_DOWN_MESSAGE) return counters.add { droppedOversize++ }
        val message = when (val d = Wire.decode(payload, DOWN_KINDS)) {
            Wire.Garbage -> return counters.add { droppedGarbage++ }
            Wire.Oversize -> return counters.add { droppedOversize++ }
            is Wire.Message -> d
        }
        val key = publish.topic.toString()
        val session = sessions[key] ?: run {
            if (message.kind == Wire.CLOSE || recentlyEnded.containsKey(key) || closing) return
            val created = Session(key, robot, watch = levels[2] == Topics.WATCH, user = levels[3], id = levels[4])
            sessions.putIfAbsent(key, created) ?: created.also { counters.add { sessions++ }; it.start() }
        }
        session.inbox.trySend(Received(message, now))
    }

    private fun clientGone(user: String, clientId: String) {
        for (s in sessions.values) if (s.user == user && s.clientId == clientId) s.inbox.trySend(CLIENT_GONE)
    }

    private suspend fun forgetEndedSessions() {
        while (true) {
            delay(SESSION_IDLE)
            val before = monotonicMs() - 2 * SESSION_IDLE.inWholeMilliseconds
            recentlyEnded.entries.removeIf { it.value < before }
        }
    }

    private class Received(val message: Wire.Message, val atMs: Long)

    // ---- sessions ---------------------------------------------------------------------------------------------------

    /**
     * One client session: a link of its own to the robot, opened at the session's first message. Down messages are
     * handled in order by one coroutine (age check, the watch rule, then to the robot); the robot's frames go up
     * from another, state and debug frames batched for at most [BrokerOptions.upBatchWindow].
     */
    private inner class Session(val key: String, val robot: Served, val watch: Boolean, val user: String, val id: String) {
        private val upTopic = Topics.session(name, robot.id, Topics.UP, user, id)
        val inbox = Channel<Received>(Channel.UNLIMITED)
        @Volatile var clientId: String? = null
        @Volatile var drives = false
        @Volatile private var transport: Transport? = null
        @Volatile private var ended = false
        private var offsetMs = Long.MAX_VALUE

        fun start() = scope.launch {
            val t = try {
                robot.device.open()
            } catch (e: Exception) {
                end("cannot open ${robot.device.name}: ${e.message}")
                return@launch
            }
            transport = t
            if (ended) return@launch t.close()
            link.publish(upTopic, Wire.frames(monotonicMs(), emptyList()))  // opened
            launch { up(t) }
            while (!ended) {
                val next = withTimeoutOrNull(SESSION_IDLE) { inbox.receiveCatching() } ?: return@launch end("no message for $SESSION_IDLE")
                val r = next.getOrNull() ?: return@launch  // ended meanwhile
                val m = r.message
                if (m === CLIENT_GONE.message) return@launch end(null)
                offsetMs = minOf(offsetMs, r.atMs - m.timeMs)
                if (m.kind != Wire.CLOSE && r.atMs - m.timeMs - offsetMs > options.maxFrameAge.inWholeMilliseconds) {
                    counters.add { droppedLate++ }
                    continue
                }
                when (m.kind) {
                    Wire.CLOSE -> return@launch end(null)
                    Wire.OPEN -> clientId = m.text
                    Wire.FRAMES -> for (f in m.frames) {
                        if (watch && !watcherMaySend(f)) {
                            counters.add { droppedNotAllowed++ }
                            continue
                        }
                        try {
                            t.send(f)
                        } catch (e: Exception) {
                            return@launch end("the robot's link was lost: ${e.message}")
                        }
                        counters.add { framesDown++ }
                    }
                }
            }
        }

        /** The robot's frames to the client, state and debug frames batched. */
        @OptIn(ExperimentalCoroutinesApi::class)  // select's onTimeout: unchanged since kotlinx.coroutines 1.7
        private suspend fun up(t: Transport) {
            val batch = ArrayList<ByteArray>()
            var batchBytes = 0
            var flushAt = 0L
            fun flush() {
                if (batch.isEmpty()) return
                link.publish(upTopic, Wire.frames(monotonicMs(), batch))
                val n = batch.size
                counters.add { framesUp += n; messagesUp++ }
                batch.clear()
                batchBytes = 0
            }
            while (true) {
                // select, not withTimeoutOrNull around a receive: a frame taken just as the window times out would
                // be lost with the cancelled receive (6-8 % of the states at 100 Hz, measured by the fleet bench).
                val next: ChannelResult<ByteArray>? = if (batch.isEmpty()) t.incoming.receiveCatching()
                else select {
                    t.incoming.onReceiveCatching { it }
                    onTimeout((flushAt - monotonicMs()).coerceAtLeast(0)) { null }
                }
                if (next == null) { flush(); continue }
                val frame = next.getOrNull()
                if (frame == null) {
                    flush()
                    end("the robot's link closed" + (next.exceptionOrNull()?.let { ": ${it.message}" } ?: ""))  // no-op after our own close
                    return
                }
                if (frame.isEmpty()) continue
                val type = frame[0].toInt() and 0xFF
                if (type == Driver.TYPE) driverSaid(frame)
                if (batch.isEmpty()) flushAt = monotonicMs() + options.upBatchWindow.inWholeMilliseconds
                batch += frame
                batchBytes += frame.size + 2
                if (type !in BATCHED_TYPES || batchBytes > MAX_UP_BATCH_BYTES || monotonicMs() >= flushAt) flush()
            }
        }

        private fun driverSaid(frame: ByteArray) {
            val packet = (Frames.decode(frame) as? org.pocketbot.protocol.FrameResult.Decoded)?.packet as? Driver ?: return
            drives = HostRole.fromCode(packet.role) == HostRole.DRIVE
            updateLease(robot, packet.label)
        }

        /** Ends the session; [reason] (null: the client ended it) goes to the client in a `closed` message. */
        fun end(reason: String?) {
            if (ended) return
            ended = true
            sessions.remove(key, this)
            recentlyEnded[key] = monotonicMs()
            transport?.close()
            inbox.close()
            if (reason != null) link.publish(upTopic, Wire.text(Wire.CLOSED, monotonicMs(), reason))
            if (drives) {
                drives = false
                updateLease(robot, "")
            }
        }
    }

    /** A watching session may send what the protocol lets a watcher send, but never ask for the drive. */
    private fun watcherMaySend(frame: ByteArray): Boolean {
        val spec = PACKET_SPECS[frame[0].toInt() and 0xFF] ?: return false
        if (spec.fromRobot || !spec.watcherOk) return false
        return spec.type != SetRole.TYPE || frame.size > Frames.HEADER_SIZE && frame[Frames.HEADER_SIZE].toInt() == HostRole.WATCH.code
    }

    /** The counters behind [stats], changed under one lock so that each snapshot is whole. */
    private class Counters {
        var sessions = 0
        var framesUp = 0L
        var messagesUp = 0L
        var framesDown = 0L
        var droppedGarbage = 0L
        var droppedOversize = 0L
        var droppedUnknownRobot = 0L
        var droppedLate = 0L
        var droppedNotAllowed = 0L
        val flow = MutableStateFlow(snapshot())

        fun add(change: Counters.() -> Unit) = synchronized(this) {
            change()
            flow.value = snapshot()
        }

        private fun snapshot() = GatewayStats(sessions, framesUp, messagesUp, framesDown, droppedGarbage,
            droppedOversize, droppedUnknownRobot, droppedLate, droppedNotAllowed)
    }

    private companion object {
        val OFFLINE_STATUS = """{"online":false}""".encodeToByteArray()
        val SESSION_KINDS = setOf(Topics.DOWN, Topics.WATCH)
        val DOWN_KINDS = setOf(Wire.FRAMES, Wire.OPEN, Wire.CLOSE)
        val SESSION_IDLE = 5.seconds
        val CLOSE_TIMEOUT = 2.seconds
        /** state_full, state_reduced, debug_text: the frames that stream, and wait to share a message. */
        val BATCHED_TYPES = setOf(StateFull.TYPE, StateReduced.TYPE, DebugText.TYPE)
        const val MAX_UP_BATCH_BYTES = 8 * 1024
        val CLIENT_GONE = Received(Wire.Message(Wire.CLOSE, 0, emptyList(), "client gone"), 0)
        val VERSION: String = Gateway::class.java.getResource("/org/pocketbot/sdk/mqtt/version.txt")?.readText()?.trim() ?: "unknown"
    }
}

/**
 * Starts a gateway named [name] (letters, digits, `.`, `-` and `_`) on the broker of [options], serving every robot
 * [devices] finds (an emulator's discoverer, an [org.pocketbot.sdk.transport.EmulatorDiscoverer], serial ports...).
 * A robot's id is its device name made topic-safe; a name seen twice gets `-2`, `-3`... Throws [BrokerException]
 * when the first connect fails.
 */
public suspend fun CoroutineScope.startGateway(name: String, options: BrokerOptions, devices: Discoverer): Gateway {
    require(Topics.isSafe(name) && name != Topics.CLIENTS) { "gateway name \"$name\" must be letters, digits, '.', '-' or '_' (and not \"clients\")" }
    val gateway = Gateway(name, options, this)
    try {
        gateway.start(devices)
    } catch (e: Throwable) {
        gateway.close()
        throw e
    }
    return gateway
}

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

package org.pocketbot.sdk.mqtt

import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.channels.ReceiveChannel
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.sdk.mqtt.internal.Topics
import org.pocketbot.sdk.mqtt.internal.Wire
import org.pocketbot.sdk.mqtt.internal.monotonicMs
import org.pocketbot.sdk.mqtt.internal.randomHex
import org.pocketbot.sdk.transport.DroppedFrames
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport
import org.pocketbot.sdk.transport.TransportLostException
import kotlin.time.Duration.Companion.seconds

/**
 * A robot a gateway serves through the broker: [open] starts a session, a link of its own to the robot through the
 * gateway, which [org.pocketbot.sdk.connect] drives as any other. Made by a [BrokerClient].
 *
 * @property gateway the gateway's name.
 * @property robot the robot's id at that gateway.
 */
public class BrokerRobotDevice internal constructor(
    private val client: BrokerClient,
    public val gateway: String,
    public val robot: String,
) : RobotDevice {
    /** The robot's advertised name (from the gateway's announcement), or `<gateway>/<robot>` before it is known. */
    override val name: String get() = client.robotName(gateway, robot) ?: "$gateway/$robot"

    /** `mqtt://<broker host:port>/<gateway>/<robot>`. */
    override val address: String = "mqtt://${client.options.hostPort}/$gateway/$robot"

    /**
     * Opens a session through the gateway and waits for the gateway to open the robot's link. Throws
     * [TransportLostException] saying why when it cannot: the broker is not connected, the gateway is offline or does
     * not answer, it serves no such robot, or the robot has no free link.
     */
    override suspend fun open(): Transport {
        fun fail(why: String): Nothing = throw TransportLostException("$address: $why")
        if (!client.connected.value) fail("not connected to the broker ${client.options.url}")
        if (!client.gatewayOnline(gateway)) fail("gateway $gateway is not online")
        if (!client.robotAnnounced(gateway, robot)) fail("gateway $gateway serves no robot $robot")
        val transport = BrokerTransport(client, gateway, robot, address)
        client.register(transport)
        transport.sendControl(Wire.OPEN, client.clientId)
        val opened = withTimeoutOrNull(OPEN_TIMEOUT) { transport.opened.await() }
        if (opened == null) {
            transport.close()
            fail("gateway $gateway did not answer within $OPEN_TIMEOUT")
        }
        return transport
    }

    override fun toString(): String = "$name ($address)"
    override fun equals(other: Any?): Boolean =
        other is BrokerRobotDevice && other.client === client && other.gateway == gateway && other.robot == robot
    override fun hashCode(): Int = (gateway.hashCode() * 31 + robot.hashCode()) * 31 + System.identityHashCode(client)

    private companion object {
        val OPEN_TIMEOUT = 3.seconds
    }
}

/**
 * One session: a link to the robot through the gateway. Frames go down one per message (the SDK waits for acks, so
 * there is nothing to batch), with the MQTT 5 expiry of [BrokerOptions.maxFrameAge]; up messages arrive through
 * [BrokerClient], which hands them to [received] on the MQTT client's thread.
 */
internal class BrokerTransport(
    private val client: BrokerClient,
    val gateway: String,
    val robot: String,
    override val address: String,
) : Transport {
    val session: String = randomHex(8)
    private val downTopic = Topics.session(gateway, robot, if (client.options.watchOnly) Topics.WATCH else Topics.DOWN, client.user, session)
    private val frames = Channel<ByteArray>(INCOMING_CAPACITY)
    @Volatile private var closed = false
    private val dropped = MutableStateFlow(DroppedFrames())

    override val droppedFrames: StateFlow<DroppedFrames> get() = dropped

    /** Completed by the gateway's first answer; failed when it says the session is closed. */
    val opened = CompletableDeferred<Unit>()

    override val incoming: ReceiveChannel<ByteArray> get() = frames

    override suspend fun send(frame: ByteArray) {
        if (closed) throw TransportLostException("$address: the session is closed")
        if (!client.connected.value) throw TransportLostException("$address: not connected to the broker")
        client.link.publish(downTopic, Wire.frames(monotonicMs(), listOf(frame)), expirySeconds = client.link.expirySeconds)
    }

    fun sendControl(kind: Int, text: String) =
        client.link.publish(downTopic, Wire.text(kind, monotonicMs(), text), expirySeconds = client.link.expirySeconds)

    /** An up message for this session; on the MQTT client's thread. */
    fun received(payload: ByteArray) {
        val message = when (val decoded = Wire.decode(payload, BrokerClient.UP_KINDS)) {
            // Only the gateway may write here (the broker's ACL), so this is a broken or hostile gateway: counted
            // where Robot.linkStats adds up what a link dropped, and survived.
            Wire.Garbage -> return dropped.update { DroppedFrames(it.tooLong, it.badFraming + 1) }
            Wire.Oversize -> return dropped.update { DroppedFrames(it.tooLong + 1, it.badFraming) }
            is Wire.Message -> decoded
        }
        when (message.kind) {
            Wire.FRAMES -> {
                opened.complete(Unit)
                // A consumer this far behind has lost the link in all but name: frames are dropped as a link drops them.
                for (f in message.frames) frames.trySend(f)
            }
            Wire.CLOSED -> lost("the gateway closed the session: ${message.text}")
        }
    }

    /** The session ended without [close]: [incoming] ends with a [TransportLostException] saying [reason]. */
    fun lost(reason: String) {
        if (closed) return
        closed = true
        client.unregister(this)
        val e = TransportLostException("$address: $reason")
        opened.completeExceptionally(e)
        frames.close(e)
    }

    override fun close() {
        if (closed) return
        closed = true
        client.unregister(this)
        if (client.connected.value) sendControl(Wire.CLOSE, "")
        opened.completeExceptionally(TransportLostException("$address: closed while opening"))
        frames.close()
    }

    private companion object {
        const val INCOMING_CAPACITY = 4096
    }
}

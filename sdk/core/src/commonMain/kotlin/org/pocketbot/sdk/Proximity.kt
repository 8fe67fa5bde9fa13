package org.pocketbot.sdk

import kotlinx.coroutines.channels.BufferOverflow
import kotlinx.coroutines.flow.MutableSharedFlow
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.SharedFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asSharedFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.IrReceived
import org.pocketbot.protocol.IrSend
import org.pocketbot.sdk.internal.EMPTY_STATE
import org.pocketbot.sdk.internal.link.LinkPort

/** True when this receiver sees an obstacle by its own IR reflection (no robot's beacon). */
public val RobotState.ProximitySide.seesObstacle: Boolean get() = ProximityFlag.OBSTACLE in flags

/** True when this receiver hears another robot's beacon ([RobotState.ProximitySide.robotId] says which). */
public val RobotState.ProximitySide.hearsRobot: Boolean get() = ProximityFlag.ROBOT in flags

/**
 * Another robot seen by one of our IR receivers.
 *
 * @property robotId the other robot's id (its settings.identity.robot_id).
 * @property side which of our receivers heard it.
 * @property orientation which LED of the other robot we saw: [IrLed.REAR] means it drives away from us, [IrLed.FRONT]
 *   that it faces us. Null for a code this SDK does not know.
 * @property distance rough distance class, from the lowest IR power it was heard at.
 * @property timeMs robot time of the state that reported it (ms).
 */
public class Encounter internal constructor(
    public val robotId: Int,
    public val side: Side,
    public val orientation: IrLed,
    public val distance: DistanceClass,
    public val timeMs: Long,
) {
    override fun equals(other: Any?): Boolean = other is Encounter && robotId == other.robotId && side == other.side &&
        orientation == other.orientation && distance == other.distance && timeMs == other.timeMs

    override fun hashCode(): Int = listOf(robotId, side, orientation, distance, timeMs).hashCode()
    override fun toString(): String = "Encounter(robot $robotId on the ${side.name.lowercase()}, facing ${orientation.name.lowercase()}, ${distance.name.lowercase()}, at $timeMs ms)"
}

/**
 * An IR message another robot sent with [Proximity.send].
 *
 * @property powerPercent the sender's transmit power.
 */
public class IrMessage internal constructor(
    public val senderId: Int,
    public val side: Side,
    public val senderLed: IrLed,
    public val powerPercent: Int,
    payload: ByteArray,
) {
    private val bytes = payload.copyOf()

    /** The payload, 0..8 bytes (a copy). */
    public val payload: ByteArray get() = bytes.copyOf()

    override fun toString(): String = "IrMessage(from $senderId on $side, led $senderLed, $powerPercent %, ${bytes.size} bytes)"
}

/**
 * IR proximity: robots announce themselves with IR beacons (id, LED, power) and detect obstacles by their own
 * reflection. [encounters] reports when a receiver starts hearing a robot or what it hears changes; [messages]
 * reports payloads sent by other robots.
 */
public class Proximity internal constructor(private val link: LinkPort) {
    private val _state = MutableStateFlow(EMPTY_STATE.proximity)
    private val _encounters = MutableSharedFlow<Encounter>(extraBufferCapacity = 64, onBufferOverflow = BufferOverflow.DROP_OLDEST)
    private val _messages = MutableSharedFlow<IrMessage>(extraBufferCapacity = 64, onBufferOverflow = BufferOverflow.DROP_OLDEST)

    /** What the front and rear receivers see (full state only). */
    public val state: StateFlow<RobotState.Proximity> = _state.asStateFlow()

    /** New or changed sightings of other robots. */
    public val encounters: SharedFlow<Encounter> = _encounters.asSharedFlow()

    /** Payloads received from other robots. */
    public val messages: SharedFlow<IrMessage> = _messages.asSharedFlow()

    /** True while the front receiver sees an obstacle by its own reflection. */
    public val obstacleFront: Boolean get() = _state.value.front.seesObstacle

    /** True while the rear receiver sees an obstacle by its own reflection. */
    public val obstacleRear: Boolean get() = _state.value.rear.seesObstacle

    /**
     * Sends [payload] (at most 8 bytes) with the next IR beacons at [powerPercent] (1..100) to robots nearby;
     * suspends until the robot accepted it.
     */
    public suspend fun send(payload: ByteArray, powerPercent: Int = 100) {
        require(payload.size <= 8) { "an IR payload has at most 8 bytes, not ${payload.size}" }
        require(powerPercent in 1..100) { "powerPercent $powerPercent is outside 1..100" }
        link.command(IrSend(powerPercent, payload.copyOf()))
    }

    internal fun update(s: RobotState.Proximity, timeMs: Long) {
        val before = _state.value
        _state.value = s
        check(Side.FRONT, before.front, s.front, timeMs)
        check(Side.REAR, before.rear, s.rear, timeMs)
    }

    private fun check(side: Side, before: RobotState.ProximitySide, now: RobotState.ProximitySide, timeMs: Long) {
        val hears = now.hearsRobot && now.robotId != 0
        if (!hears) return
        val heard = before.hearsRobot && before.robotId != 0
        if (heard && before.robotId == now.robotId && before.robotLed == now.robotLed && before.distance == now.distance) return
        _encounters.tryEmit(Encounter(now.robotId, side, now.robotLed, now.distance, timeMs))
    }

    internal fun received(p: IrReceived) {
        _messages.tryEmit(IrMessage(p.senderId, Side.fromCode(p.side), IrLed.fromCode(p.senderLed), p.power, p.data))
    }
}

package org.pocketbot.sdk

import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.LocoMode
import org.pocketbot.protocol.StateLocomotion
import org.pocketbot.protocol.Stop
import org.pocketbot.protocol.WheelSpeeds
import kotlin.random.Random

/**
 * A movement queued on the robot, identified by [id] (the movement id in `move_*`, `movement_done` and
 * state.locomotion).
 */
public class MovementHandle internal constructor(
    private val robot: Robot,
    /** The movement id, 1..65535. */
    public val id: Int,
    /** What was queued. */
    public val movement: Movement,
) {
    internal val result = CompletableDeferred<MovementResult>()

    /** True once the movement finished or was cancelled. */
    public val isDone: Boolean get() = result.isCompleted

    /**
     * Suspends until the movement finished or was cancelled by [Locomotion.stop]. Survives link losses: after a
     * reconnect the SDK checks state.locomotion.finished_id.
     *
     * @throws RobotClosedException when the robot is closed first.
     */
    public suspend fun await(): MovementResult = robot.awaitOrClosed(result)

    override fun toString(): String = "MovementHandle(#$id $movement)"
}

/**
 * Locomotion (thesis 6.5): a queue of movements executed by the firmware, and teleoperation.
 *
 * ```
 * repeat(4) {
 *     robot.locomotion.enqueue(Movement.Straight(distanceM = 0.10, speedMps = 0.2))
 *     robot.locomotion.enqueue(Movement.Rotate(angleDeg = 90.0, speedMps = 0.2))
 * }
 * robot.locomotion.awaitIdle()
 * ```
 */
public class Locomotion internal constructor(private val robot: Robot) {
    private val _state = MutableStateFlow(StateLocomotion(0, 0, 0, 0))
    private val outstanding = ArrayDeque<MovementHandle>()
    private var lastId = Random.nextInt(1, 0xFFFF)
    private var lastFinishedSeen = -1

    /** Mode, queue length, current and last finished movement id, as the robot reported them. */
    public val state: StateFlow<StateLocomotion> = _state.asStateFlow()

    /** What drives the motors now, or null for a code this SDK does not know. */
    public val mode: LocoMode? get() = LocoMode.fromCode(_state.value.mode)

    /**
     * Queues [movement] behind the ones already queued; suspends until the robot acknowledged it (not until it
     * finished: use [MovementHandle.await] or [awaitIdle]).
     *
     * @throws CommandRefusedException when the robot refuses it (e.g. `QUEUE_FULL`, `BAD_ARGUMENT`).
     */
    public suspend fun enqueue(movement: Movement): MovementHandle = enqueue(movement, null)

    internal suspend fun enqueue(movement: Movement, beforeFirstSend: (suspend () -> Unit)?): MovementHandle {
        val handle = robot.serial {
            lastId = lastId % 0xFFFF + 1
            MovementHandle(robot, lastId, movement).also { outstanding.addLast(it) }
        }
        try {
            robot.command(movement.toPacket(handle.id), beforeFirstSend)
        } catch (e: Throwable) {
            robot.serial { outstanding.remove(handle) }
            handle.result.completeExceptionally(e)
            throw e
        }
        return handle
    }

    /** Suspends until every movement this host queued so far finished or was cancelled. */
    public suspend fun awaitIdle() {
        val handles = robot.serial { outstanding.toList() }
        for (h in handles) h.await()
    }

    /**
     * Clears the robot's queue and stops: braking on the speed profile, or with [immediate] motors off at once.
     * Also ends teleoperation and line following. Queued movements end as [MovementResult.CANCELLED].
     */
    public suspend fun stop(immediate: Boolean = false) {
        robot.command(Stop(if (immediate) 1 else 0))
        robot.serial {
            while (outstanding.isNotEmpty()) outstanding.removeFirst().result.complete(MovementResult.CANCELLED)
        }
    }

    /**
     * Teleoperation: the robot holds these wheel speeds (m/s, per-wheel PID) until the next command, or until its
     * link failsafe stops it after settings.link.failsafe_timeout_ms without any packet (the SDK's heartbeat keeps
     * the failsafe quiet while the link is up). Not acknowledged; returns false when the link is down.
     */
    public suspend fun setWheelSpeeds(leftMps: Double, rightMps: Double): Boolean =
        robot.sendUnacked(WheelSpeeds(leftMps.toFloat(), rightMps.toFloat()))

    internal fun finished(id: Int) {
        val index = outstanding.indexOfFirst { it.id == id }
        if (index < 0) return
        // The firmware runs its queue in order: everything before this one finished too.
        repeat(index + 1) { outstanding.removeFirst().result.complete(MovementResult.FINISHED) }
    }

    internal fun update(state: StateLocomotion) {
        _state.value = state
        if (state.finishedId != lastFinishedSeen) {
            // Only a change counts: a stale finished_id from an earlier session must not finish a new movement.
            if (lastFinishedSeen != -1 && state.finishedId != 0) finished(state.finishedId)
            lastFinishedSeen = state.finishedId
        }
    }
}

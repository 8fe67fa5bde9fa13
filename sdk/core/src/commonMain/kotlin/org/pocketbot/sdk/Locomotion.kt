package org.pocketbot.sdk

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.first
import org.pocketbot.protocol.MoveArc
import org.pocketbot.protocol.MoveRotate
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.MovementDone
import org.pocketbot.protocol.MovementLog
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.ReadMovements
import org.pocketbot.protocol.Settings
import org.pocketbot.protocol.Stop
import org.pocketbot.protocol.WheelSpeeds
import org.pocketbot.sdk.internal.EMPTY_STATE
import org.pocketbot.sdk.internal.link.CommandWithdrawnException
import org.pocketbot.sdk.internal.link.LinkPort
import kotlin.math.PI
import kotlin.random.Random
import kotlin.time.Duration.Companion.milliseconds

/**
 * A movement queued on the robot. It always ends, with the truth: [await] returns how it ended and how much of it
 * was done, as the robot reported it (see [MovementOutcome]).
 */
public class MovementHandle internal constructor(
    private val link: LinkPort,
    /** The movement id, 1..65535 (in `move_*`, `movement_done` and state.locomotion). */
    public val id: Int,
    /** What was queued. */
    public val movement: Movement,
) {
    internal val result = CompletableDeferred<MovementResult>()

    /** The robot acknowledged it: it was in its queue. */
    internal var acked = false

    /** Withdrawn by a stop after it went out: the robot may or may not have it. */
    internal var uncertain = false

    /** The robot no longer held it at the last look: declared lost unless its log shows it at the next. */
    internal var missing = false

    /** How much of it this host saw done (from the encoders while the robot reported it running), or null. */
    internal var seenDone: Double? = null

    /** How many state updates had arrived when it ended: [Locomotion.awaitSettled] waits for one more, at rest. */
    internal var endedAtState = -1L

    /** True once it ended. */
    public val isDone: Boolean get() = result.isCompleted

    /** How it ended, or null while it has not. */
    @OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)
    public val resultOrNull: MovementResult? get() = if (result.isCompleted) result.getCompleted() else null

    /**
     * Suspends until the movement ended and returns how. Survives link losses: after a reconnect the SDK reads the
     * robot's movement log and ends every handle the robot no longer holds.
     *
     * @throws RobotClosedException when the robot is closed first.
     */
    public suspend fun await(): MovementResult = link.awaitOrClosed(result)

    override fun toString(): String = "MovementHandle(#$id $movement${resultOrNull?.let { ": $it" } ?: ""})"
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
 *
 * **The link failsafe.** The robot stops host-driven motion on its own when it hears nothing from the host for
 * settings.link.failsafe_timeout_ms (1000 ms by default; 0 turns it off): the running movement is cut where it is,
 * the queue is cleared, teleoperation stops, and line following stops unless settings.line_follow.autonomous. While
 * the link is up the SDK's heartbeat keeps the failsafe quiet, so it trips only when the link is down for longer
 * than the timeout. Every movement it ends reports [MovementOutcome.FAILSAFE] with the distance or angle done, and
 * [mode] says [LocoMode.FAILSAFE] until the next command. A shorter outage changes nothing: the movement goes on
 * and finishes once. Change the timeout with `robot.settings.link.failsafeTimeoutMs.set(ms)`.
 */
public class Locomotion internal constructor(
    private val link: LinkPort,
    random: Random,
    /** The robot's settings as the host knows them (geometry, for what this host sees a movement do). */
    private val settings: () -> Settings,
) {
    private val _state = MutableStateFlow(EMPTY_STATE.locomotion)
    private val _queue = MutableStateFlow<List<MovementHandle>>(emptyList())
    private val outstanding = ArrayList<MovementHandle>()
    private var lastId = random.nextInt(1, 0xFFFF)
    private var stopGeneration = 0
    private var logWaiter: CompletableDeferred<MovementLog>? = null
    private var heldIds: Set<Int> = emptySet()
    private var logCheck: kotlinx.coroutines.Job? = null
    private var idleSinceMs = -1L

    // The running movement as this host watches it: its handle, and the encoder counts when it was first seen running.
    private var running: MovementHandle? = null
    private var startLeft = 0
    private var startRight = 0
    private var lastLeft = 0
    private var lastRight = 0
    private var lastTimeMs = -1L

    // State updates so far, and whether the last one had both wheels standing: what awaitSettled waits on.
    private val statesSeen = MutableStateFlow(StatesSeen(0, false))

    /** Mode, queue length, current and last finished movement id, as the robot reported them (full state only). */
    public val state: StateFlow<RobotState.Locomotion> = _state.asStateFlow()

    /** What drives the motors now. */
    public val mode: LocoMode get() = _state.value.mode

    /** The movements this host queued that have not ended yet, in order: the robot's queue as this host knows it. */
    public val queue: StateFlow<List<MovementHandle>> = _queue.asStateFlow()

    /**
     * Queues [movement] behind the ones already queued; suspends until the robot acknowledged it (not until it
     * finished: use [MovementHandle.await] or [awaitIdle]).
     *
     * @throws CommandRefusedException when the robot refuses it (e.g. `QUEUE_FULL`, `BAD_ARGUMENT`).
     */
    public suspend fun enqueue(movement: Movement): MovementHandle = enqueue(movement, null)

    internal suspend fun enqueue(movement: Movement, beforeFirstSend: (suspend () -> Unit)?): MovementHandle {
        val (handle, generation) = link.serial {
            lastId = lastId % 0xFFFF + 1
            val h = MovementHandle(link, lastId, movement)
            outstanding += h
            publish()
            h to stopGeneration
        }
        try {
            link.command(movement.toPacket(handle.id), wanted = { stopGeneration == generation }, beforeFirstSend = beforeFirstSend)
            link.serial { handle.acked = true }
        } catch (e: CommandWithdrawnException) {
            link.serial {
                if (e.everSent) {
                    // It went out but was never acknowledged: the robot's log says whether it got there.
                    handle.uncertain = true
                    checkLogSoon()
                } else {
                    end(handle, MovementOutcome.DROPPED, 0.0, "withdrawn by a stop before it was sent")
                }
            }
        } catch (e: Throwable) {
            link.serial {
                outstanding.remove(handle)
                publish()
            }
            handle.result.completeExceptionally(e)
            throw e
        }
        return handle
    }

    /**
     * Runs [program] on the robot, in order, however long it is, and returns how each movement ended. The robot holds
     * at most [QUEUE_CAPACITY] movements (the running one included); this queues as many as fit, then the next as
     * each one ends, so the robot always has the next movement at hand and drives the program without a pause between
     * movements. When a movement does not finish (a stop, the failsafe, a restart) the rest of the program is not
     * sent: the result list ends with that movement and those the robot dropped with it.
     *
     * ```
     * val square = List(4) { listOf(Movement.Straight(0.10, 0.2), Movement.Rotate(90.0, 0.2)) }.flatten()
     * robot.locomotion.runProgram(square + square + square)   // 24 movements
     * ```
     *
     * [org.pocketbot.sdk.Fleet.runTogether] starts programs on several robots at the same moment.
     *
     * @throws CommandRefusedException when the robot refuses a movement.
     */
    public suspend fun runProgram(program: List<Movement>): List<MovementResult> = feed(emptyList(), program.iterator())

    /** Runs the program whose first movements are [queued] already and whose others are [rest] (see [runProgram]). */
    internal suspend fun feed(queued: List<MovementHandle>, rest: Iterator<Movement>): List<MovementResult> {
        val open = ArrayDeque(queued)
        val results = ArrayList<MovementResult>()
        var ended = false
        while (true) {
            while (!ended && rest.hasNext() && link.serial { outstanding.size } < QUEUE_CAPACITY) open.addLast(enqueue(rest.next()))
            val next = open.removeFirstOrNull()
            if (next == null) {
                if (ended || !rest.hasNext()) return results
                // Movements queued before the program fill the robot's queue: wait until one of them ends.
                link.serial { outstanding.firstOrNull() }?.await()
                continue
            }
            val result = next.await()
            results += result
            if (result.outcome != MovementOutcome.FINISHED) ended = true
        }
    }

    /**
     * Suspends until every movement this host queued so far has ended. It returns on the robot's report of the last
     * one (`movement_done`), which comes before the state that carries the final wheel counts: [Robot.odometry] and
     * [Robot.state] may still show the robot a little short of where it stopped. [awaitSettled] waits for that state.
     */
    public suspend fun awaitIdle() {
        val handles = link.serial { outstanding.toList() }
        for (h in handles) h.await()
    }

    /**
     * Suspends until every movement this host queued so far has ended (as [awaitIdle]) and the robot then reported a
     * state with both wheels at rest: the encoder counts in [Robot.state], [Robot.odometry] and
     * [Robot.motors] are then those the robot stopped at, and later states say the same until the robot moves again.
     * Returns at once when nothing was queued and the last state showed the robot at rest.
     *
     * ```
     * robot.locomotion.enqueue(Movement.Straight(distanceM = 0.10, speedMps = 0.2))
     * robot.locomotion.awaitSettled()
     * println(robot.odometry.pose.value)   // where the robot stopped
     * ```
     *
     * It needs the robot's state reports: with [org.pocketbot.protocol.SyncMode.NONE] none comes and it waits for
     * ever (bound it with a timeout). Reduced states do (they carry the encoders and wheel speeds).
     *
     * @throws RobotClosedException when the robot is closed first.
     */
    public suspend fun awaitSettled() {
        val handles = link.serial { outstanding.toList() }
        for (h in handles) h.await()
        val after = link.serial { handles.maxOfOrNull { it.endedAtState } ?: -1L }
        val settled = CompletableDeferred<Unit>()
        val watch = link.launch {
            statesSeen.first { it.count > after && it.atRest }
            settled.complete(Unit)
        }
        try {
            link.awaitOrClosed(settled)
        } finally {
            watch.cancel()
        }
    }

    /**
     * Stops the robot: clears its queue and brakes the running movement along the speed profile, or with
     * [immediate] turns the motors off at once. Also ends teleoperation and line following. The stop goes out ahead
     * of everything, even during an outage (then first after the reconnect); movements queued on this host and not
     * yet sent are withdrawn. Suspends until the robot acknowledged the stop; each movement then ends as
     * [MovementOutcome.STOPPED] (the running one, with how far it got) or [MovementOutcome.DROPPED].
     */
    public suspend fun stop(immediate: Boolean = false) {
        link.serial { stopGeneration++ }
        link.urgent(Stop(if (immediate) 1 else 0))
    }

    /**
     * Teleoperation: the robot holds these wheel speeds (m/s, per-wheel PID) until the next command, or until its
     * link failsafe stops it (see above). Clears the movement queue. Not acknowledged; returns false when the link is
     * down.
     */
    public suspend fun setWheelSpeeds(leftMps: Double, rightMps: Double): Boolean {
        require(leftMps.isFinite() && rightMps.isFinite()) { "wheel speeds must be finite" }
        return link.sendUnacked(WheelSpeeds(leftMps.toFloat(), rightMps.toFloat()))
    }

    // ---- what the robot reports (on the link's serial context) ----

    internal fun reported(p: MovementDone) {
        val index = outstanding.indexOfFirst { it.id == p.id }
        if (index < 0) return
        val h = outstanding[index]
        val outcome = MovementOutcome.fromCode(p.outcome)
        end(h, outcome, p.done.toDouble(), describe(outcome))
        // The robot reports in queue order: an earlier movement still open lost its report on the way.
        if ((0 until index).any { outstanding.getOrNull(it)?.acked == true }) checkLogSoon()
    }

    /**
     * A frame from the robot was lost: if it was a `movement_done`, nothing else says so while the robot sends
     * reduced state or none, so the log is read once the robot had time to settle.
     */
    internal fun reportMayBeLost() {
        if (outstanding.any { it.acked }) checkLogSoon()
    }

    internal fun logArrived(log: MovementLog) {
        logWaiter?.complete(log) ?: settle(log, resumed = true)
    }

    /**
     * Every state update: what the running movement did so far, as this host sees it in the encoder counts (kept for
     * when the robot cannot tell any more: a restart).
     */
    internal fun watch(encoders: RobotState.Encoders, timeMs: Long, atRest: Boolean) {
        statesSeen.value = StatesSeen(statesSeen.value.count + 1, atRest)
        if (lastTimeMs >= 0 && timeMs < lastTimeMs) running = null // the robot restarted: its counts begin again
        lastTimeMs = timeMs
        lastLeft = encoders.left
        lastRight = encoders.right
        val h = running ?: return
        val s = settings()
        val left = (lastLeft - startLeft) * s.metresPerPulse
        val right = (lastRight - startRight) * s.metresPerPulse
        h.seenDone = when (h.movement) {
            is Movement.Straight -> (left + right) / 2
            is Movement.Rotate, is Movement.Arc -> (right - left) / s.geometry.wheelBaseM * 180 / PI
        }
    }

    internal fun update(s: RobotState.Locomotion, timeMs: Long) {
        _state.value = s
        if (running?.id != s.currentId) {
            running = outstanding.firstOrNull { it.id == s.currentId }
            startLeft = lastLeft
            startRight = lastRight
        }
        // A robot that stands idle while movements are open lost their reports: its log knows.
        val idle = s.queueLength == 0 && s.currentId == 0
        if (!idle || outstanding.none { it.acked }) {
            idleSinceMs = -1
            return
        }
        if (idleSinceMs < 0 || timeMs < idleSinceMs) idleSinceMs = timeMs
        else if (timeMs - idleSinceMs >= SETTLE_MS) {
            idleSinceMs = -1
            checkLogSoon()
        }
    }

    /**
     * After a reconnect or a robot reset: ends every handle the robot no longer holds, with what its log says. A robot
     * that [restarted] knows nothing of the movements before: they end at once as lost, with what this host saw.
     */
    internal suspend fun reconcile(exchange: suspend (Packet) -> Unit, resumed: Boolean, restarted: Boolean) {
        val waiter = CompletableDeferred<MovementLog>()
        logWaiter = waiter
        try {
            exchange(ReadMovements)
        } finally {
            logWaiter = null
        }
        // The log comes before the ack on the same ordered link.
        @OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)
        val log = if (waiter.isCompleted) waiter.getCompleted() else null
        settle(log ?: throw RobotException("the robot acknowledged read_movements without its log"), resumed, restarted)
    }

    internal fun robotHolds(packet: Packet): Boolean = when (packet) {
        is MoveStraight -> packet.id in heldIds
        is MoveRotate -> packet.id in heldIds
        is MoveArc -> packet.id in heldIds
        else -> false
    }

    private fun settle(log: MovementLog, resumed: Boolean, restarted: Boolean = false) {
        val entries = HashMap<Int, Pair<MovementOutcome, Float>>()
        for (i in 0 until log.count.coerceIn(0, log.ids.size)) entries[log.ids[i]] = MovementOutcome.fromCode(log.outcomes[i]) to log.done[i]
        for (h in outstanding.toList()) {
            val e = entries[h.id] ?: continue
            end(h, e.first, e.second.toDouble(), describe(e.first))
        }
        // The robot's queue is the running movement and the ones this host queued after it.
        val at = if (log.currentId != 0) outstanding.indexOfFirst { it.id == log.currentId } else -1
        val held = if (at >= 0) outstanding.subList(at, minOf(outstanding.size, at + maxOf(1, log.queueLength))).toSet() else emptySet()
        heldIds = entries.keys + held.map { it.id }
        var suspects = false
        for (h in outstanding.toList()) {
            when {
                h in held -> h.missing = false
                h.uncertain -> end(h, MovementOutcome.DROPPED, 0.0, "withdrawn by a stop; it never reached the robot")
                !h.acked -> {} // its command is still on its way and goes out again after the reconnect
                restarted -> end(h, MovementOutcome.LOST, h.seenDone, lostDetail(h, "the robot restarted"))
                h.missing -> end(
                    h, MovementOutcome.LOST, h.seenDone,
                    lostDetail(h, if (resumed) "the robot has no record of it" else "the robot has no record of it: it was reset or served another host"),
                )
                else -> {
                    h.missing = true
                    suspects = true
                }
            }
        }
        // A movement that just ended is reported once the robot stands still: look again after that.
        if (suspects) checkLogSoon()
    }

    /** Reads the movement log once the robot had time to settle; at most one such look is pending at a time. */
    private fun checkLogSoon() {
        if (logCheck?.isActive == true) return
        logCheck = link.launch {
            delay(SETTLE_MS.milliseconds)
            try {
                link.command(ReadMovements)
            } catch (e: CancellationException) {
                throw e
            } catch (e: Throwable) {
                link.debugLog.host(1, "reading the movement log failed: ${e.message}")
            }
        }
    }

    private fun end(h: MovementHandle, outcome: MovementOutcome, done: Double?, detail: String) {
        h.endedAtState = statesSeen.value.count
        if (!h.result.complete(MovementResult(h.movement, outcome, done, detail))) return
        outstanding.remove(h)
        if (running === h) running = null
        publish()
    }

    private fun lostDetail(h: MovementHandle, why: String): String =
        h.seenDone?.let { "$why; this host saw it do ${round3(it)} ${h.movement.unit} before it lost track" } ?: why

    private fun publish() {
        _queue.value = outstanding.toList()
    }

    private class StatesSeen(val count: Long, val atRest: Boolean)

    public companion object {
        /**
         * How many movements a robot holds, the running one included: one more is refused with `QUEUE_FULL` until
         * one ends. [runProgram] and [org.pocketbot.sdk.Fleet.runTogether] feed longer programs as the queue drains.
         */
        public const val QUEUE_CAPACITY: Int = 16

        /** Longer than the robot takes to stand still and report after a movement ends (about 300 ms at most). */
        private const val SETTLE_MS = 500L

        private fun describe(o: MovementOutcome): String = when (o) {
            MovementOutcome.FINISHED -> "finished"
            MovementOutcome.STOPPED -> "stopped by a host's command"
            MovementOutcome.FAILSAFE -> "cut by the robot's link failsafe: no packet from the host for link.failsafe_timeout_ms"
            MovementOutcome.DROPPED -> "cleared from the queue before it started"
            MovementOutcome.LOST -> "the robot has no record of it"
        }
    }
}

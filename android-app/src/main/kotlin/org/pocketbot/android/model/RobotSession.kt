package org.pocketbot.android.model

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.SharingStarted
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.combine
import kotlinx.coroutines.flow.stateIn
import kotlinx.coroutines.launch
import kotlinx.coroutines.plus
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.LocoMode
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotState

/** What the status bar shows of the connected robot, always: battery and link. */
class RobotStatus(
    val name: String,
    /** Battery voltage in volts; 0 until the first full state. */
    val batteryV: Double,
    val link: ConnectionState,
) {
    /** Charge left, 0..100 %, from the voltage (a LiPo cell: 3.4 V empty, 4.1 V full). */
    val batteryPercent: Int get() = (((batteryV - EMPTY_V) / (FULL_V - EMPTY_V)) * 100).toInt().coerceIn(0, 100)

    val linkUp: Boolean get() = link == ConnectionState.Connected

    /** The link in a few words. */
    val linkText: String get() = when (val l = link) {
        ConnectionState.Connecting -> "connecting"
        ConnectionState.Connected -> "connected"
        is ConnectionState.Lost -> "link lost"
        is ConnectionState.Reconnecting -> "reconnecting (${l.attempt})"
        is ConnectionState.Closed -> "disconnected"
    }

    private companion object {
        const val EMPTY_V = 3.4
        const val FULL_V = 4.1
    }
}

/**
 * Whether what the screens show of the robot is live: the robot reports, over a link that is up. Otherwise every
 * value is the last one heard, [ageMs] old, and the screens grey it and say so ([why]).
 */
data class Freshness(val live: Boolean, val ageMs: Long, val why: String?) {
    /** "4 s" (whole seconds, as people read an age). */
    val age: String get() = "${ageMs / 1000} s"
}

/** What kind of link a robot is reached over, in a few words, and whether the user should be warned about it. */
data class LinkKind(val text: String, val warning: Boolean = false)

/** A robot device that can say what kind of link it opened (e.g. an insecure RFCOMM socket). */
interface DescribedLink {
    /** The link in use, or null before one opened. */
    val linkKind: StateFlow<LinkKind?>
}

/** The message of a failure, for the user: never an empty string. */
fun failure(e: Throwable): String = e.message?.takeIf { it.isNotBlank() } ?: e::class.simpleName ?: "unknown error"

/**
 * The connected robot and what each screen does with it. Everything goes through the SDK's public API; failures
 * become notices ([tell]), never crashes. Lives in the app's scope, so it survives the Activity.
 *
 * @param whyLost what the app knows about a lost link beyond the SDK's reason (Bluetooth switched off), or null.
 */
class RobotSession(
    val robot: Robot,
    parent: CoroutineScope,
    private val tell: (String, Notice.Kind) -> Unit,
    val whyLost: () -> String? = { null },
) {
    /** Everything this session started; cancelled by [close]. */
    val scope: CoroutineScope = parent + SupervisorJob(parent.coroutineContext[Job])

    val name: String = robot.identity.name
    val address: String = robot.identity.address
    val firmware: String = robot.identity.firmwareVersion

    /** The kind of link, where the transport says (Bluetooth: secure or insecure RFCOMM). */
    val linkKind: StateFlow<LinkKind?> = (robot.device as? DescribedLink)?.linkKind ?: MutableStateFlow(null)

    val status: StateFlow<RobotStatus> = combine(robot.power.reading, robot.connection) { power: RobotState.Power, link ->
        RobotStatus(name, power.batteryMv / 1000.0, link)
    }.stateIn(scope, SharingStarted.Eagerly, RobotStatus(name, 0.0, robot.connection.value))

    private val _freshness = MutableStateFlow(Freshness(live = true, ageMs = 0, why = null))

    /** Live, or how old the values shown are and why; re-evaluated every [FRESHNESS_TICK_MS]. */
    val freshness: StateFlow<Freshness> = _freshness.asStateFlow()

    val lineSensor = LineSensorModel(robot, scope)
    val calibration = CalibrationModel(robot, scope, ::act)
    val joystick = JoystickModel(robot, scope, ::act)
    val lineFollow = LineFollowModel(robot, scope, ::act)
    val trajectory = TrajectoryModel(robot, scope, ::act)

    /** True while the robot drives under the user's hand (the joystick held, a movement, line following): the screen stays on. */
    val driving: StateFlow<Boolean> = combine(joystick.state, robot.locomotion.state, robot.connection) { stick, loco, link ->
        stick.held || (link == ConnectionState.Connected && loco.mode in DRIVING)
    }.stateIn(scope, SharingStarted.Eagerly, false)

    init {
        scope.launch {
            var wasUp = true
            robot.connection.collect { state ->
                when (state) {
                    is ConnectionState.Lost -> if (wasUp) tell(
                        whyLost() ?: "Link to $name lost (${state.reason}). The robot stops on its own within a second; reconnecting…",
                        Notice.Kind.ERROR,
                    )
                    ConnectionState.Connected -> if (!wasUp) tell("Link to $name is back.", Notice.Kind.INFO)
                    is ConnectionState.Closed -> state.cause?.let { tell("$name: gave up reconnecting: ${failure(it)}", Notice.Kind.ERROR) }
                    else -> {}
                }
                wasUp = state == ConnectionState.Connected
            }
        }
        // The age of what the robot reported, counted in ticks of this scope's clock (the phone's, or a test's).
        var ticks = 0L
        var heardAt = 0L
        scope.launch { robot.stateUpdates.collect { heardAt = ticks } }
        scope.launch {
            while (true) {
                delay(FRESHNESS_TICK_MS)
                ticks++
                val age = (ticks - heardAt) * FRESHNESS_TICK_MS
                val link = robot.connection.value
                _freshness.value = when {
                    link != ConnectionState.Connected -> Freshness(false, age, status.value.linkText)
                    age > maxOf(STALE_AFTER_MS, 3L * robot.settings.sync.periodMs.value) -> Freshness(false, age, "the robot stopped reporting")
                    else -> Freshness(true, age, null)
                }
            }
        }
    }

    /** Stops the robot: movements, teleoperation and line following end. */
    fun stopRobot() {
        joystick.release()
        act("stop") { robot.locomotion.stop() }
    }

    /** Runs [block], telling the user when it fails: no failure of a robot action may end the app. */
    fun act(what: String, block: suspend () -> Unit) {
        scope.launch {
            try {
                block()
            } catch (e: CancellationException) {
                throw e
            } catch (e: Exception) {
                tell("$name: $what failed: ${failure(e)}", Notice.Kind.ERROR)
            }
        }
    }

    /** Stops the robot and disconnects it; suspends until it is done. */
    suspend fun close() {
        joystick.release()
        try {
            if (robot.connection.value == ConnectionState.Connected) robot.locomotion.stop()
        } catch (e: CancellationException) {
            throw e
        } catch (e: Exception) {
            // The robot could not be told: its link failsafe stops it once the link is closed.
        }
        scope.cancel()
        try {
            robot.disconnect()
        } catch (e: Exception) {
            tell("$name: disconnecting failed: ${failure(e)}", Notice.Kind.ERROR)
        }
    }

    private companion object {
        val DRIVING = setOf(LocoMode.MOVEMENT, LocoMode.TELEOP, LocoMode.LINE_FOLLOW, LocoMode.TRACK)
        const val FRESHNESS_TICK_MS = 250L

        /** Silent this long (or three state periods, if longer) and the robot has stopped reporting: 10 of its default 100 ms periods. */
        const val STALE_AFTER_MS = 1000L
    }
}

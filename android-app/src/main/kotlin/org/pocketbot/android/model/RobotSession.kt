package org.pocketbot.android.model

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.flow.SharingStarted
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.combine
import kotlinx.coroutines.flow.stateIn
import kotlinx.coroutines.launch
import kotlinx.coroutines.plus
import org.pocketbot.protocol.StatePower
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotException

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
    val scope: CoroutineScope = parent + SupervisorJob(parent.coroutineContext[kotlinx.coroutines.Job])

    val name: String = robot.identity.name
    val address: String = robot.identity.address
    val firmware: String = robot.identity.firmwareVersion

    val status: StateFlow<RobotStatus> = combine(robot.power.reading, robot.connection) { power: StatePower, link ->
        RobotStatus(name, power.batteryMv / 1000.0, link)
    }.stateIn(scope, SharingStarted.Eagerly, RobotStatus(name, 0.0, robot.connection.value))

    val lineSensor = LineSensorModel(robot, scope)
    val calibration = CalibrationModel(robot, scope)
    val joystick = JoystickModel(robot, scope)
    val lineFollow = LineFollowModel(robot, scope, ::act)
    val trajectory = TrajectoryModel(robot, scope, ::act)

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
                    is ConnectionState.Closed -> state.cause?.let { tell("$name: gave up reconnecting: ${it.message}", Notice.Kind.ERROR) }
                    else -> {}
                }
                wasUp = state == ConnectionState.Connected
            }
        }
    }

    /** Stops the robot: movements, teleoperation and line following end. */
    fun stopRobot() {
        joystick.release()
        act("stop") { robot.locomotion.stop() }
    }

    /** Runs [block], telling the user when it fails. */
    fun act(what: String, block: suspend () -> Unit) {
        scope.launch {
            try {
                block()
            } catch (e: CancellationException) {
                throw e
            } catch (e: RobotException) {
                tell("$name: $what: ${e.message}", Notice.Kind.ERROR)
            } catch (e: IllegalArgumentException) {
                tell("$name: $what: ${e.message}", Notice.Kind.ERROR)
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
        } catch (e: RobotException) {
            // The robot could not be told: its link failsafe stops it once the link is closed.
        }
        scope.cancel()
        robot.disconnect()
    }
}

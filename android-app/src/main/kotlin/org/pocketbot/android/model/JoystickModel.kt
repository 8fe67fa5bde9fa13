package org.pocketbot.android.model

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotException
import kotlin.math.hypot

/** The joystick's state: where the knob is, the wheel speeds it asks for, and why it stopped if it did. */
data class JoystickState(
    /** Knob deflection, -1 left .. 1 right. */
    val x: Double = 0.0,
    /** Knob deflection, -1 back .. 1 forward. */
    val y: Double = 0.0,
    val held: Boolean = false,
    val leftMps: Double = 0.0,
    val rightMps: Double = 0.0,
    /** Top wheel speed at full deflection, m/s. */
    val maxSpeedMps: Double = JoystickModel.DEFAULT_MAX_SPEED_MPS,
    /** Why driving stopped on its own (the link was lost), or null. */
    val stoppedBecause: String? = null,
)

/**
 * Teleoperation with a dead-man: the robot drives only while the knob is held. The knob's position becomes wheel
 * speeds (forward plus or minus turn, as a tank drive), sent at most every [SEND_PERIOD_MS] ms however fast the
 * finger moves. Releasing the knob, leaving the screen (the screen calls [release]) or losing the link stops the
 * robot: a stop command on the SDK's urgent lane, which goes out first after a reconnect, and meanwhile the robot's
 * own link failsafe.
 */
class JoystickModel(private val robot: Robot, private val scope: CoroutineScope) {
    private val _state = MutableStateFlow(JoystickState())
    private var sender: Job? = null

    val state: StateFlow<JoystickState> = _state.asStateFlow()

    init {
        scope.launch {
            robot.connection.collect { link ->
                if (link != ConnectionState.Connected && _state.value.held) {
                    stop("the link was lost: the robot stops on its own (its failsafe), and on a stop command once the link is back")
                }
            }
        }
    }

    fun setMaxSpeed(mps: Double) {
        _state.update { it.copy(maxSpeedMps = mps.coerceIn(MIN_SPEED_MPS, MAX_SPEED_MPS)) }
    }

    /** The finger is on the knob at ([x], [y]), each -1..1 (clamped to the circle). */
    fun move(x: Double, y: Double) {
        if (robot.connection.value != ConnectionState.Connected) {
            _state.update { it.copy(stoppedBecause = "no link to the robot: driving waits until it is back") }
            return
        }
        val r = hypot(x, y)
        val (cx, cy) = if (r > 1) x / r to y / r else x to y
        val max = _state.value.maxSpeedMps
        // Tank drive: full forward is both wheels at max; full right turns in place.
        val left = ((cy + cx) * max).coerceIn(-max, max)
        val right = ((cy - cx) * max).coerceIn(-max, max)
        _state.update { it.copy(x = cx, y = cy, held = true, leftMps = left, rightMps = right, stoppedBecause = null) }
        if (sender?.isActive != true) sender = scope.launch { send() }
    }

    /** The finger left the knob, or the screen is left: the robot stops. */
    fun release() {
        if (!_state.value.held && sender?.isActive != true) return
        stop(null)
    }

    private fun stop(reason: String?) {
        sender?.cancel()
        sender = null
        _state.update { it.copy(x = 0.0, y = 0.0, held = false, leftMps = 0.0, rightMps = 0.0, stoppedBecause = reason) }
        scope.launch {
            try {
                robot.locomotion.stop()
            } catch (e: CancellationException) {
                throw e
            } catch (e: RobotException) {
                // Closed meanwhile: the robot's failsafe stops it.
            }
        }
    }

    /** Sends the wheel speeds whenever they changed, at most once per [SEND_PERIOD_MS]. */
    private suspend fun send() {
        var sent: Pair<Double, Double>? = null
        while (_state.value.held) {
            val s = _state.value
            val wanted = s.leftMps to s.rightMps
            if (wanted != sent) {
                robot.locomotion.setWheelSpeeds(wanted.first, wanted.second)
                sent = wanted
            }
            delay(SEND_PERIOD_MS)
        }
    }

    companion object {
        /** Wheel speed commands are at most this often, in ms (20 a second: smooth, and a small share of the link). */
        const val SEND_PERIOD_MS: Long = 50
        const val DEFAULT_MAX_SPEED_MPS: Double = 0.2
        const val MIN_SPEED_MPS: Double = 0.05
        const val MAX_SPEED_MPS: Double = 0.5
    }
}

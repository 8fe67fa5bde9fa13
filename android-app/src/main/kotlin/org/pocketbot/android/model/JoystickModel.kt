package org.pocketbot.android.model

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.Robot
import kotlin.math.abs
import kotlin.math.hypot
import kotlin.math.sign

/** The joystick's state: where the knob is, the wheel speeds it asks for, and why it stopped if it did. */
data class JoystickState(
    /** Knob deflection, -1 left .. 1 right. */
    val x: Double = 0.0,
    /** Knob deflection, -1 back .. 1 forward. */
    val y: Double = 0.0,
    val held: Boolean = false,
    /** The wheel speeds sent now, m/s: on their ramp towards what the knob asks. */
    val leftMps: Double = 0.0,
    val rightMps: Double = 0.0,
    /** Top wheel speed at full deflection, m/s. */
    val maxSpeedMps: Double = JoystickModel.DEFAULT_MAX_SPEED_MPS,
    /** Why driving stopped on its own (the link was lost), or null. */
    val stoppedBecause: String? = null,
)

/** A short drive that ends by itself: the joystick's alternative for TalkBack (and anyone who prefers buttons). */
enum class Step(val label: String) {
    FORWARD("Forward 10 cm"), BACK("Back 10 cm"), LEFT("Turn left 45°"), RIGHT("Turn right 45°");

    fun movement(speedMps: Double): Movement = when (this) {
        FORWARD -> Movement.Straight(STEP_M, speedMps)
        BACK -> Movement.Straight(-STEP_M, speedMps)
        LEFT -> Movement.Rotate(STEP_DEG, speedMps)
        RIGHT -> Movement.Rotate(-STEP_DEG, speedMps)
    }

    private companion object {
        const val STEP_M = 0.10
        const val STEP_DEG = 45.0
    }
}

/**
 * Teleoperation with a dead-man: the robot drives only while the knob is held. The knob's position becomes wheel
 * speeds (forward plus or minus turn, as a tank drive): a dead zone around the centre asks for nothing, and speeding
 * up follows a ramp ([RAMP_MPS_PER_S]) instead of jumping to where the finger landed; slowing down is immediate. The
 * speeds are sent at most every [SEND_PERIOD_MS] ms however fast the finger moves. Releasing the knob, leaving the
 * screen (the screen calls [release]) or losing the link stops the robot: a stop command on the SDK's urgent lane,
 * which goes out first after a reconnect, and meanwhile the robot's own link failsafe.
 *
 * [step] drives a fixed distance or angle that ends by itself, for people who cannot hold and drag.
 */
class JoystickModel(
    private val robot: Robot,
    private val scope: CoroutineScope,
    private val act: (String, suspend () -> Unit) -> Unit,
) {
    private val _state = MutableStateFlow(JoystickState())
    private var sender: Job? = null
    private var target = 0.0 to 0.0

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
        // Outside the dead zone the deflection is measured from its edge, so speed grows from 0 there.
        val live = ((minOf(r, 1.0) - DEAD_ZONE) / (1 - DEAD_ZONE)).coerceAtLeast(0.0)
        val (dx, dy) = if (r > 0) cx / minOf(r, 1.0) * live to cy / minOf(r, 1.0) * live else 0.0 to 0.0
        val max = _state.value.maxSpeedMps
        // Tank drive: full forward is both wheels at max; full right turns in place.
        target = ((dy + dx) * max).coerceIn(-max, max) to ((dy - dx) * max).coerceIn(-max, max)
        _state.update { it.copy(x = cx, y = cy, held = true, stoppedBecause = null) }
        if (sender?.isActive != true) sender = scope.launch { send() }
    }

    /** The finger left the knob, or the screen is left: the robot stops. */
    fun release() {
        if (!_state.value.held && sender?.isActive != true) return
        stop(null)
    }

    /** Drives [step] at the top speed; it ends by itself. */
    fun step(step: Step) {
        release()
        act(step.label.lowercase()) { robot.locomotion.enqueue(step.movement(_state.value.maxSpeedMps)) }
    }

    private fun stop(reason: String?) {
        sender?.cancel()
        sender = null
        target = 0.0 to 0.0
        _state.update { it.copy(x = 0.0, y = 0.0, held = false, leftMps = 0.0, rightMps = 0.0, stoppedBecause = reason) }
        // Closed meanwhile: the robot's failsafe stops it; any other failure is told.
        act("stop") { robot.locomotion.stop() }
    }

    /** Every [SEND_PERIOD_MS]: the wheel speeds one ramp step closer to the target, sent when they changed. */
    private suspend fun send() {
        var sent: Pair<Double, Double>? = null
        val stepMps = RAMP_MPS_PER_S * SEND_PERIOD_MS / 1000.0
        while (_state.value.held) {
            val s = _state.value
            val now = ramp(s.leftMps, target.first, stepMps) to ramp(s.rightMps, target.second, stepMps)
            _state.update { it.copy(leftMps = now.first, rightMps = now.second) }
            if (now != sent) {
                robot.locomotion.setWheelSpeeds(now.first, now.second)
                sent = now
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

        /** Deflections below this share of the radius ask for nothing: a resting thumb does not creep. */
        const val DEAD_ZONE: Double = 0.15

        /** How fast a wheel speed may grow, m/s per second: the default top speed is reached in 0.4 s. */
        const val RAMP_MPS_PER_S: Double = 0.5

        /** [current] one [step] closer to [wanted] when that is faster (or the other way), at once when slower. */
        fun ramp(current: Double, wanted: Double, step: Double): Double = when {
            abs(wanted) <= abs(current) && sign(wanted) * sign(current) >= 0 -> wanted
            sign(wanted) * sign(current) < 0 -> 0.0 // reversing: through standstill first
            else -> current + sign(wanted) * minOf(step, abs(wanted - current))
        }
    }
}

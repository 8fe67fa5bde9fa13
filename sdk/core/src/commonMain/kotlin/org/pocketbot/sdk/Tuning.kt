package org.pocketbot.sdk

import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.map
import kotlinx.coroutines.launch
import kotlinx.coroutines.yield
import org.pocketbot.protocol.PACKET_SPECS
import kotlin.math.abs
import kotlin.math.sqrt
import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds

/** The robot's PID controllers a user tunes (thesis 6.6): what each one measures, and its gains. */
public enum class Controller(public val title: String, public val unit: String) {
    /** Robot speed: the mean of both wheel speeds, towards the running movement's cruise speed. */
    ROBOT_SPEED("robot speed", "m/s"),

    /** Wheel balance: left minus right wheel speed, towards 0 on a straight run. */
    WHEEL_BALANCE("wheel balance", "m/s"),

    /** Per-wheel speed: the left wheel's speed, towards the teleoperation speed (the right wheel has the same gains). */
    WHEEL_SPEED("wheel speed", "m/s"),

    /** Line following: the line position under the sensor, towards 0 (centred), in -1 .. 1. */
    LINE("line position", "");

    /** The gains of this controller in [settings]. */
    public fun gains(settings: RobotSettings): PidSettings = when (this) {
        ROBOT_SPEED -> settings.speedPid
        WHEEL_BALANCE -> settings.wheelBalance
        WHEEL_SPEED -> settings.wheelPid
        LINE -> settings.linePid
    }

    /** What this controller measures in [state] (reduced states carry all of it). */
    public fun measure(state: RobotState): Double = when (this) {
        ROBOT_SPEED -> (state.wheels.speedLeftMmps + state.wheels.speedRightMmps) / 2000.0
        WHEEL_BALANCE -> (state.wheels.speedLeftMmps - state.wheels.speedRightMmps) / 1000.0
        WHEEL_SPEED -> state.wheels.speedLeftMmps / 1000.0
        LINE -> state.line.position / 1000.0
    }
}

/** One sample of a controller at robot time [timeMs]: what it was asked for and what it measured. */
public class TuningSample(public val timeMs: Long, public val setpoint: Double, public val measured: Double) {
    override fun equals(other: Any?): Boolean =
        other is TuningSample && timeMs == other.timeMs && setpoint == other.setpoint && measured == other.measured
    override fun hashCode(): Int = (timeMs.hashCode() * 31 + setpoint.hashCode()) * 31 + measured.hashCode()
    override fun toString(): String = "$timeMs ms: set $setpoint, measured $measured"
}

/**
 * A captured step response: every sample of [controller] while [Tuner.stepTest] ran its manoeuvre, with the usual
 * figures of merit. [step] is the setpoint of the step (the cruise or wheel speed; 0 for the line and wheel balance,
 * whose figures are then the error around 0).
 */
public class StepResponse(
    public val controller: Controller,
    public val step: Double,
    public val samples: List<TuningSample>,
    /** The gains the robot ran with: kp, ki, kd. */
    public val gains: List<Double>,
) {
    /** Time from the step until the measured value first reached 90 % of it, or null (no step, or never reached). */
    public val riseTimeMs: Long? get() {
        if (step == 0.0 || samples.isEmpty()) return null
        val start = samples.firstOrNull { it.setpoint != 0.0 } ?: return null
        val reached = samples.firstOrNull { it.timeMs >= start.timeMs && it.measured / step >= 0.9 } ?: return null
        return reached.timeMs - start.timeMs
    }

    /** Largest measured value beyond the step, in percent of it (0 when it never went beyond), or null without a step. */
    public val overshootPercent: Double? get() {
        if (step == 0.0 || samples.isEmpty()) return null
        val peak = samples.maxOf { it.measured / step }
        return ((peak - 1) * 100).coerceAtLeast(0.0)
    }

    /** Root mean square of setpoint minus measured over the samples while the setpoint was held (all, without a step). */
    public val rmsError: Double get() {
        val held = if (step == 0.0) samples else samples.filter { it.setpoint != 0.0 }
        if (held.isEmpty()) return 0.0
        return sqrt(held.sumOf { (it.setpoint - it.measured).let { e -> e * e } } / held.size)
    }

    /** The samples as CSV: `time_ms,setpoint,measured`, one line per sample after a header. */
    public fun toCsv(): String = buildString {
        append("time_ms,setpoint,measured\n")
        for (s in samples) append(s.timeMs).append(',').append(s.setpoint).append(',').append(s.measured).append('\n')
    }

    override fun toString(): String = "StepResponse(${controller.title}, ${samples.size} samples, rise ${riseTimeMs} ms, " +
        "overshoot ${overshootPercent?.let { "${(it * 10).toInt() / 10.0} %" }}, rms error $rmsError)"
}

/**
 * How big a [Tuner.stepTest] is: the speed of its step, and how far or how long the robot moves.
 *
 * - robot speed and wheel balance: [distanceM] straight at [speedMps] (a movement, on its speed profile);
 * - wheel speed: both wheels at [speedMps] for [duration] (teleoperation), then 0;
 * - line: line following at [speedMps] for [duration] (the robot must be on a line).
 */
public class StepSize(public val speedMps: Double, public val distanceM: Double, public val duration: Duration) {
    init {
        require(speedMps > 0 && speedMps <= MAX_SPEED_MPS) { "a step's speed must be in (0, $MAX_SPEED_MPS] m/s, was $speedMps" }
        require(distanceM > 0 && distanceM <= MAX_DISTANCE_M) { "a step's distance must be in (0, $MAX_DISTANCE_M] m, was $distanceM" }
        require(duration.isPositive() && duration <= MAX_DURATION) { "a step's duration must be in (0, $MAX_DURATION], was $duration" }
    }

    /** What the robot will do for [controller], for people to confirm: it moves, and needs room (and a line). */
    public fun describe(controller: Controller): String {
        val v = speedMps.toDecimalString()
        val s = (duration.inWholeMilliseconds / 1000.0).toDecimalString()
        return when (controller) {
            Controller.ROBOT_SPEED, Controller.WHEEL_BALANCE -> "drives ${distanceM.toDecimalString()} m straight ahead at $v m/s"
            Controller.WHEEL_SPEED -> "drives straight ahead at $v m/s for $s s (about ${(speedMps * duration.inWholeMilliseconds / 1000).roundTo(2)} m)"
            Controller.LINE -> "follows the line at $v m/s for $s s: put it on a line first"
        }
    }

    override fun equals(other: Any?): Boolean =
        other is StepSize && speedMps == other.speedMps && distanceM == other.distanceM && duration == other.duration

    override fun hashCode(): Int = (speedMps.hashCode() * 31 + distanceM.hashCode()) * 31 + duration.hashCode()
    override fun toString(): String = "StepSize($speedMps m/s, $distanceM m, $duration)"

    public companion object {
        /** The fastest step: the robot's top speed. */
        public const val MAX_SPEED_MPS: Double = 0.5

        /** The longest movement of a step. */
        public const val MAX_DISTANCE_M: Double = 2.0

        /** The longest step. */
        public val MAX_DURATION: Duration = 10.seconds

        /** The standard step of [controller]: 30 cm at 0.2 m/s, the wheels at 0.15 m/s for 1 s, or 2 s of line following at 0.15 m/s. */
        public fun defaultFor(controller: Controller): StepSize = when (controller) {
            Controller.ROBOT_SPEED, Controller.WHEEL_BALANCE -> StepSize(0.2, 0.3, 1.seconds)
            Controller.WHEEL_SPEED -> StepSize(0.15, 0.15, 1.seconds)
            Controller.LINE -> StepSize(0.15, 0.3, 2.seconds)
        }
    }
}

private fun Double.roundTo(places: Int): String {
    var scale = 1.0
    repeat(places) { scale *= 10 }
    return (kotlin.math.round(this * scale) / scale).toDecimalString()
}

/**
 * PID tuning for one robot: fast samples of a [Controller] (setpoint and measured value) and a standard step test.
 *
 * ```
 * val tuner = Tuner(robot)
 * tuner.begin()                                   // reduced state at the fastest rate the link carries
 * val response = tuner.stepTest(Controller.ROBOT_SPEED, StepSize(speedMps = 0.2, distanceM = 0.3, duration = 1.seconds))
 * robot.settings.speedPid.kp.set(response.gains[0] * 1.2)
 * tuner.end()                                     // the sync mode the robot had before
 * ```
 */
public class Tuner(private val robot: Robot) {
    private val commanded = MutableStateFlow<Double?>(null)
    private var before: Pair<SyncMode, Duration>? = null

    /**
     * The movement of a robot speed step test, once the robot has it: the setpoint follows its speed profile. A flow
     * rather than a plain field, because the step test sets it while other threads read the setpoint.
     */
    private val profile = MutableStateFlow<SpeedProfile?>(null)

    /** The step [stepTest] asks of the controller now (its cruise speed, or 0 after it), or null while no step test runs. */
    public val stepSetpoint: StateFlow<Double?> = commanded.asStateFlow()

    /**
     * The period of reduced state while tuning: the shortest at which reduced states fill at most 60 % of the
     * robot's link ([org.pocketbot.sdk.transport.RobotDevice.linkRate]), so commands, their answers and heartbeats
     * still fit. 4 ms (250 samples a second) on the PocketBot2's 115200 Bd link.
     */
    public val samplePeriod: Duration = robot.device.linkRate.periodFor(REDUCED_PAYLOAD, LINK_SHARE)

    /**
     * Switches the robot to reduced state every [samplePeriod], remembering its sync mode for [end]. Reduced states
     * carry the wheel speeds and the line position, all any controller measures.
     */
    public suspend fun begin() {
        if (before == null) before = robot.reflector.mode.value to robot.reflector.period.value
        robot.reflector.set(SyncMode.REDUCED, samplePeriod)
    }

    /** Gives the robot back the sync mode it had before [begin]. */
    public suspend fun end() {
        val (mode, period) = before ?: return
        before = null
        robot.reflector.set(mode, period)
    }

    /**
     * Every state update of the robot as a sample of [controller]. The setpoint is the step test's while one runs (for
     * the robot speed, the speed its profile asks for at that moment: accelerating, cruising, braking); otherwise
     * the running movement's cruise speed for [Controller.ROBOT_SPEED] and 0 for the others.
     */
    public fun samples(controller: Controller): Flow<TuningSample> = robot.stateUpdates.map { sampleOf(controller, it) }

    /** [update] as a sample of [controller], with the setpoint of this moment (see [samples]). */
    public fun sampleOf(controller: Controller, update: StateUpdate): TuningSample =
        TuningSample(update.timeMs, setpointOf(controller, update.state), controller.measure(update.state))

    private fun setpointOf(controller: Controller, state: RobotState): Double {
        val step = commanded.value
        // Until the robot has the step's movement it is not asked to move.
        if (controller == Controller.ROBOT_SPEED && step != null && step != 0.0) return profile.value?.speedAt(state) ?: 0.0
        return step ?: when (controller) {
            Controller.ROBOT_SPEED -> when (val m = robot.locomotion.queue.value.firstOrNull()?.movement) {
                is Movement.Straight -> m.speedMps
                is Movement.Arc -> m.speedMps
                else -> 0.0
            }
            else -> 0.0
        }
    }

    /**
     * Runs the standard manoeuvre of [controller] ([StepSize.defaultFor]) and returns every sample of it: see the
     * overload with a step size.
     */
    public suspend fun stepTest(controller: Controller): StepResponse = stepTest(controller, StepSize.defaultFor(controller))

    /**
     * Runs the manoeuvre of [controller] at [size] (see [StepSize]) and returns every sample of it, from the step until
     * the robot stood still again. The robot moves: give it room (ask the user first: [StepSize.describe] says what
     * the robot will do). Call [begin] first for fast samples.
     */
    public suspend fun stepTest(controller: Controller, size: StepSize): StepResponse = coroutineScope {
        val gains = controller.gains(robot.settings).let { listOf(it.kp.value, it.ki.value, it.kd.value) }
        val step = when (controller) {
            Controller.ROBOT_SPEED, Controller.WHEEL_SPEED -> size.speedMps
            else -> 0.0
        }
        val samples = mutableListOf<TuningSample>()
        val capture = launch { samples(controller).collect { samples += it } }
        yield() // the collector is subscribed before anything moves
        try {
            commanded.value = step
            when (controller) {
                Controller.ROBOT_SPEED, Controller.WHEEL_BALANCE -> {
                    val movement = Movement.Straight(size.distanceM, size.speedMps)
                    val handle = robot.locomotion.enqueue(movement)
                    // The robot started it at most a sample ago, from standing still.
                    profile.value = SpeedProfile(movement, robot.settings, robot.state.value)
                    handle.await()
                }
                Controller.WHEEL_SPEED -> {
                    // Teleoperation holds until the next command; sent again now and then so a lost datagram does not
                    // leave the wheels at the old speed.
                    val steps = (size.duration.inWholeMilliseconds / RESEND_MS).coerceAtLeast(1)
                    repeat(steps.toInt()) {
                        robot.locomotion.setWheelSpeeds(size.speedMps, size.speedMps)
                        delay(RESEND_MS)
                    }
                    commanded.value = 0.0
                    robot.locomotion.setWheelSpeeds(0.0, 0.0)
                }
                Controller.LINE -> {
                    robot.lineFollower.start(size.speedMps)
                    delay(size.duration)
                    robot.lineFollower.stop()
                }
            }
            commanded.value = 0.0
            delay(SETTLE_MS)
        } finally {
            commanded.value = null
            profile.value = null
            capture.cancel()
        }
        StepResponse(controller, step, samples.toList(), gains)
    }

    private companion object {
        val REDUCED_PAYLOAD = PACKET_SPECS.values.single { it.name == "state_reduced" }.maxSize
        const val LINK_SHARE = 0.6
        private const val RESEND_MS = 250L
        private const val SETTLE_MS = 400L
    }
}

/**
 * The speed a movement's three-segment profile asks for (as the firmware's locomotion computes it): from
 * profile.min_speed_mps up at profile.accel_mps2 to the cruise speed, and down so as to reach the minimum speed at
 * the end, v^2 = vmin^2 + 2 * decel * remaining; 0 once the distance is done. Robot time and distance count from
 * [start], the last state before the robot began it, standing still.
 */
private class SpeedProfile(movement: Movement.Straight, settings: RobotSettings, private val start: RobotState) {
    private val cruise = movement.speedMps
    private val distance = abs(movement.distanceM)
    private val accel = settings.profile.accelMps2.value
    private val decel = settings.profile.decelMps2.value
    private val vmin = minOf(settings.profile.minSpeedMps.value, cruise)
    private val metresPerPulse = settings.store.values.value.metresPerPulse

    fun speedAt(state: RobotState): Double {
        val seconds = (state.time.timeMs - start.time.timeMs).coerceAtLeast(0) / 1000.0
        val pulses = (state.encoders.left - start.encoders.left) + (state.encoders.right - start.encoders.right)
        val remaining = distance - abs(pulses / 2.0 * metresPerPulse)
        if (remaining <= 0) return 0.0
        return minOf(cruise, vmin + accel * seconds, sqrt(vmin * vmin + 2 * decel * remaining))
    }
}

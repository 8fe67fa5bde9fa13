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
import org.pocketbot.protocol.RobotState
import org.pocketbot.protocol.SyncMode
import kotlin.math.sqrt
import kotlin.time.Duration

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
 * PID tuning for one robot: fast samples of a [Controller] (setpoint and measured value) and a standard step test.
 *
 * ```
 * val tuner = Tuner(robot)
 * tuner.begin()                                   // reduced state at the fastest rate the link carries
 * val response = tuner.stepTest(Controller.ROBOT_SPEED)
 * robot.settings.speedPid.kp.set(response.gains[0] * 1.2)
 * tuner.end()                                     // the sync mode the robot had before
 * ```
 */
public class Tuner(private val robot: Robot) {
    private val commanded = MutableStateFlow<Double?>(null)
    private var before: Pair<SyncMode, Duration>? = null

    /** What [stepTest] asks of the controller now, or null while no step test runs. */
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
     * Every state update of the robot as a sample of [controller]. The setpoint is the step test's while one runs;
     * otherwise the running movement's cruise speed for [Controller.ROBOT_SPEED] and 0 for the others.
     */
    public fun samples(controller: Controller): Flow<TuningSample> = robot.stateUpdates.map { sampleOf(controller, it) }

    /** [update] as a sample of [controller], with the setpoint of this moment (see [samples]). */
    public fun sampleOf(controller: Controller, update: StateUpdate): TuningSample =
        TuningSample(update.timeMs, setpointOf(controller), controller.measure(update.state))

    private fun setpointOf(controller: Controller): Double = commanded.value ?: when (controller) {
        Controller.ROBOT_SPEED -> when (val m = robot.locomotion.queue.value.firstOrNull()?.movement) {
            is Movement.Straight -> m.speedMps
            is Movement.Arc -> m.speedMps
            else -> 0.0
        }
        else -> 0.0
    }

    /**
     * Runs the standard manoeuvre of [controller] and returns every sample of it, from the step until the robot
     * stood still again:
     * - robot speed and wheel balance: 30 cm straight at 0.2 m/s;
     * - wheel speed: both wheels at 0.15 m/s for one second, then 0;
     * - line: two seconds of line following at settings.line_follow.speed_mps (the robot must be on a line).
     *
     * The robot moves: give it room. Call [begin] first for fast samples.
     */
    public suspend fun stepTest(controller: Controller): StepResponse = coroutineScope {
        val gains = controller.gains(robot.settings).let { listOf(it.kp.value, it.ki.value, it.kd.value) }
        val step = when (controller) {
            Controller.ROBOT_SPEED -> STEP_SPEED_MPS
            Controller.WHEEL_SPEED -> WHEEL_STEP_MPS
            else -> 0.0
        }
        val samples = mutableListOf<TuningSample>()
        val capture = launch { samples(controller).collect { samples += it } }
        yield() // the collector is subscribed before anything moves
        try {
            commanded.value = step
            when (controller) {
                Controller.ROBOT_SPEED, Controller.WHEEL_BALANCE ->
                    robot.locomotion.enqueue(Movement.Straight(STEP_DISTANCE_M, STEP_SPEED_MPS)).await()
                Controller.WHEEL_SPEED -> {
                    // Teleoperation holds until the next command; sent again now and then so a lost datagram does not
                    // leave the wheels at the old speed.
                    repeat(WHEEL_STEP_MS / RESEND_MS) {
                        robot.locomotion.setWheelSpeeds(WHEEL_STEP_MPS, WHEEL_STEP_MPS)
                        delay(RESEND_MS.toLong())
                    }
                    commanded.value = 0.0
                    robot.locomotion.setWheelSpeeds(0.0, 0.0)
                }
                Controller.LINE -> {
                    robot.lineFollower.start()
                    delay(LINE_STEP_MS)
                    robot.lineFollower.stop()
                }
            }
            commanded.value = 0.0
            delay(SETTLE_MS)
        } finally {
            commanded.value = null
            capture.cancel()
        }
        StepResponse(controller, step, samples.toList(), gains)
    }

    private companion object {
        val REDUCED_PAYLOAD = PACKET_SPECS.values.single { it.name == "state_reduced" }.maxSize
        const val LINK_SHARE = 0.6
        private const val STEP_SPEED_MPS = 0.2
        private const val STEP_DISTANCE_M = 0.3
        private const val WHEEL_STEP_MPS = 0.15
        private const val WHEEL_STEP_MS = 1000
        private const val RESEND_MS = 250
        private const val LINE_STEP_MS = 2000L
        private const val SETTLE_MS = 400L
    }
}

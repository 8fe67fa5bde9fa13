package org.pocketbot.sdk

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.Settings
import org.pocketbot.sdk.internal.link.LinkPort
import kotlin.math.PI
import kotlin.math.abs
import kotlin.math.cos
import kotlin.math.sin

/**
 * How far each wheel rolled since [Odometry.reset], in metres (signed: backwards is negative), and how far the robot's
 * centre travelled along its path ([travelledM], never negative: a turn in place adds nothing).
 */
public class WheelDistances internal constructor(public val leftM: Double, public val rightM: Double, public val travelledM: Double) {
    override fun equals(other: Any?): Boolean = other is WheelDistances && leftM == other.leftM && rightM == other.rightM && travelledM == other.travelledM
    override fun hashCode(): Int = (leftM.hashCode() * 31 + rightM.hashCode()) * 31 + travelledM.hashCode()
    override fun toString(): String = "WheelDistances(left=$leftM m, right=$rightM m, travelled=$travelledM m)"

    internal companion object {
        val ZERO = WheelDistances(0.0, 0.0, 0.0)
    }
}

/**
 * Odometry (thesis 9.8): dead reckoning from the wheel encoders in every state update (full or reduced).
 *
 * The heading comes from the total encoder counts, not from a sum of small increments, so it has no rounding drift:
 * `theta = 2*pi*r / (l*T) * (N2 - N1)` with wheel radius r, wheel base l, T pulses per revolution and N1, N2 the
 * left and right counts since [reset]. Each translation `d = pi*2r*(t1 + t2) / (2T)` is applied along the mean of
 * the headings before and after the update. r, l and T come from the robot's settings (geometry.wheel_diameter_m,
 * geometry.wheel_base_m, encoder.pulses_per_rev), read again on every update.
 *
 * **Heading convention**, the same as the emulator's ground truth (`RobotHandle.truePose`): counter-clockwise
 * positive from +x, wrapped to -180..180 degrees (-pi..pi rad), so that a robot that turned a full circle left reads
 * about 0 again, not 360. A robot's total turn is in [wheelDistances] ((right - left) / wheel base).
 *
 * Odometry starts at the origin facing +x when the robot connects; [reset] starts it at a given pose (such as where
 * the robot really stands: in the emulator `robot.odometry.reset(emulator.robot(id).truePose)`), also before the
 * first state update.
 *
 * When the robot resets (its clock starts again) its counts restart at zero: odometry keeps the pose it had and
 * counts on from the new zero; what the robot did while it was unheard is not known.
 */
public class Odometry internal constructor(private val link: LinkPort, private val settings: RobotSettings) {
    private val _pose = MutableStateFlow(Pose.ORIGIN)
    private val _wheels = MutableStateFlow(WheelDistances.ZERO)
    private var baseLeft = 0
    private var baseRight = 0
    private var lastLeft = 0
    private var lastRight = 0
    private var lastTimeMs = -1L
    private var started = false
    private var pendingReset: Pose? = Pose.ORIGIN
    private var carryLeft = 0L
    private var carryRight = 0L
    private var baseHeading = 0.0
    private var heading = 0.0 // unwrapped: the mean of two headings needs no care at +-pi
    private var x = 0.0
    private var y = 0.0
    private var travelled = 0.0

    /** The dead-reckoned pose, updated with every state update; its heading is in -pi..pi (see above). */
    public val pose: StateFlow<Pose> = _pose.asStateFlow()

    private val path = Trajectory()

    /**
     * The dead-reckoned path: a point whenever the pose moved 1 mm or turned about 1 degree (see [Trajectory]).
     * Odometry records it; [clearTrajectory] starts it again.
     */
    public val trajectory: ReadOnlyTrajectory get() = path

    /** Forgets the [trajectory] so far: it goes on from the next pose. Safe to call from any thread. */
    public fun clearTrajectory(): Unit = path.clear()

    /** The wheel distances and the distance travelled since [reset], from the encoders and the robot's geometry. */
    public val wheelDistances: StateFlow<WheelDistances> = _wheels.asStateFlow()

    /**
     * Makes the current position [pose] (default: the origin facing +x) and zeroes [wheelDistances]: the encoder
     * counts of the last state update become the new zero, so movements queued after this call all count from
     * [pose]. Before the first state update it takes effect with that update. The [trajectory] starts again from
     * [pose] (the old path was in the old frame). Safe to call from any thread.
     */
    public suspend fun reset(pose: Pose = Pose.ORIGIN) {
        link.serial {
            path.clear()
            if (started) rebase(lastLeft, lastRight, pose) else pendingReset = pose
        }
    }

    private fun rebase(left: Int, right: Int, p: Pose) {
        baseLeft = left
        baseRight = right
        carryLeft = 0
        carryRight = 0
        lastLeft = left
        lastRight = right
        baseHeading = p.headingRad
        heading = p.headingRad
        travelled = 0.0
        x = p.xM
        y = p.yM
        _pose.value = Pose(x, y, wrapAngle(heading))
        path.add(lastTimeMs, _pose.value)
        publishWheels()
    }

    /** Pulses counted since [reset], carried over robot resets. */
    private fun totalLeft(left: Int): Long = carryLeft + (left - baseLeft)
    private fun totalRight(right: Int): Long = carryRight + (right - baseRight)

    // From the decoded settings struct: read on every state update, so no per-field decoding here.
    private fun metresPerPulse(): Double = settings.store.values.value.metresPerPulse
    private fun wheelBase(): Double = settings.store.values.value.geometry.wheelBaseM.toDouble()

    internal fun update(encoders: RobotState.Encoders, timeMs: Long) {
        val reset = lastTimeMs >= 0 && timeMs < lastTimeMs
        lastTimeMs = timeMs
        if (!started) {
            rebase(encoders.left, encoders.right, pendingReset ?: Pose.ORIGIN)
            started = true
            pendingReset = null
            return
        }
        if (reset) {
            // The robot's counts start again from its new zero: carry what was counted before.
            carryLeft = totalLeft(lastLeft)
            carryRight = totalRight(lastRight)
            baseLeft = encoders.left
            baseRight = encoders.right
            lastLeft = encoders.left
            lastRight = encoders.right
            return
        }
        val metresPerPulse = metresPerPulse()
        // Int subtraction wraps like the firmware's 32-bit counters.
        val t1 = encoders.left - lastLeft
        val t2 = encoders.right - lastRight
        if (t1 == 0 && t2 == 0) return
        val before = heading
        heading = baseHeading + metresPerPulse / wheelBase() * (totalRight(encoders.right) - totalLeft(encoders.left)).toDouble()
        val d = metresPerPulse * (t1.toDouble() + t2.toDouble()) / 2.0
        val mid = (before + heading) / 2.0
        x += d * cos(mid)
        y += d * sin(mid)
        travelled += abs(d)
        lastLeft = encoders.left
        lastRight = encoders.right
        _pose.value = Pose(x, y, wrapAngle(heading))
        path.add(timeMs, _pose.value)
        publishWheels()
    }

    private fun publishWheels() {
        val m = metresPerPulse()
        _wheels.value = WheelDistances(totalLeft(lastLeft) * m, totalRight(lastRight) * m, travelled)
    }
}

/** [rad] as an angle in -pi..pi: the SDK's heading convention (see [Odometry]). */
internal fun wrapAngle(rad: Double): Double {
    val r = rad % (2 * PI)
    return when {
        r > PI -> r - 2 * PI
        r < -PI -> r + 2 * PI
        else -> r
    }
}

/** How far a wheel rolls per encoder pulse, in metres, with this geometry and encoder. */
internal val Settings.metresPerPulse: Double get() = PI * geometry.wheelDiameterM / encoder.pulsesPerRev

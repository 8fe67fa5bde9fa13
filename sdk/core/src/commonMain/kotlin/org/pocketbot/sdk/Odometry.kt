package org.pocketbot.sdk

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.StateEncoders
import kotlin.math.PI
import kotlin.math.cos
import kotlin.math.hypot
import kotlin.math.sin

/**
 * A position on the floor: [xM] and [yM] in metres, [headingRad] in radians counter-clockwise from the x axis
 * (the robot starts at the origin facing +x). [Odometry] does not wrap the heading: after a full left turn it is
 * 2*pi, so turns can be counted.
 */
public data class Pose(public val xM: Double = 0.0, public val yM: Double = 0.0, public val headingRad: Double = 0.0) {
    /** The heading in degrees. */
    public val headingDeg: Double get() = headingRad * 180.0 / PI

    /** Straight-line distance to [other] in metres. */
    public fun distanceTo(other: Pose): Double = hypot(xM - other.xM, yM - other.yM)

    override fun toString(): String {
        fun f(v: Double, digits: Int): String {
            val scale = listOf(1.0, 10.0, 100.0, 1000.0, 10000.0)[digits]
            val r = kotlin.math.round(v * scale) / scale
            return r.toString()
        }
        return "Pose(x=${f(xM * 1000, 1)} mm, y=${f(yM * 1000, 1)} mm, heading=${f(headingDeg, 2)} deg)"
    }

    public companion object {
        /** The origin, facing +x. */
        public val ORIGIN: Pose = Pose()
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
 */
public class Odometry internal constructor(private val robot: Robot) {
    private val _pose = MutableStateFlow(Pose.ORIGIN)
    private var baseLeft = 0
    private var baseRight = 0
    private var lastLeft = 0
    private var lastRight = 0
    private var started = false
    private var pendingReset: Pose? = Pose.ORIGIN
    private var baseHeading = 0.0
    private var x = 0.0
    private var y = 0.0

    /** The dead-reckoned pose, updated with every state update. */
    public val pose: StateFlow<Pose> = _pose.asStateFlow()

    /**
     * Makes the current position [pose] (default: the origin facing +x): the encoder counts of the last state
     * update become the new zero, so movements queued after this call all count from [pose]. Before the first
     * state update it takes effect with that update. Safe to call from any thread.
     */
    public suspend fun reset(pose: Pose = Pose.ORIGIN) {
        robot.serial {
            if (started) rebase(lastLeft, lastRight, pose) else pendingReset = pose
        }
    }

    private fun rebase(left: Int, right: Int, p: Pose) {
        baseLeft = left
        baseRight = right
        lastLeft = left
        lastRight = right
        baseHeading = p.headingRad
        x = p.xM
        y = p.yM
        _pose.value = p
    }

    internal fun update(encoders: StateEncoders) {
        if (!started) {
            rebase(encoders.left, encoders.right, pendingReset ?: Pose.ORIGIN)
            started = true
            pendingReset = null
            return
        }
        val s = robot.settings
        val wheelDiameter = s.geometry.wheelDiameterM.value.toDouble()
        val wheelBase = s.geometry.wheelBaseM.value.toDouble()
        val pulses = s.encoder.pulsesPerRev.value.toDouble()
        val metresPerPulse = PI * wheelDiameter / pulses
        // Int subtraction wraps like the firmware's 32-bit counters.
        val t1 = encoders.left - lastLeft
        val t2 = encoders.right - lastRight
        if (t1 == 0 && t2 == 0) return
        val before = _pose.value.headingRad
        val heading = baseHeading + metresPerPulse / wheelBase * ((encoders.right - baseRight) - (encoders.left - baseLeft)).toDouble()
        val d = metresPerPulse * (t1.toDouble() + t2.toDouble()) / 2.0
        val mid = (before + heading) / 2.0
        x += d * cos(mid)
        y += d * sin(mid)
        lastLeft = encoders.left
        lastRight = encoders.right
        _pose.value = Pose(x, y, heading)
    }
}

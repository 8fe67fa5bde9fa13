package org.pocketbot.sdk

import kotlin.math.PI
import kotlin.math.hypot
import kotlin.math.round

/**
 * A position on the floor: [xM] and [yM] in metres, [headingRad] in radians counter-clockwise from the x axis.
 * [Odometry] does not wrap the heading: after a full left turn it is 2*pi, so turns can be counted. The emulator's
 * ground truth uses the same type. Not a data class, so that a later field does not break callers: no `copy`, no
 * `componentN`.
 */
public class Pose(public val xM: Double, public val yM: Double, public val headingRad: Double) {
    /** The heading in degrees. */
    public val headingDeg: Double get() = headingRad * 180.0 / PI

    /** Straight-line distance to [other] in metres. */
    public fun distanceTo(other: Pose): Double = hypot(xM - other.xM, yM - other.yM)

    override fun equals(other: Any?): Boolean =
        other is Pose && xM == other.xM && yM == other.yM && headingRad == other.headingRad

    override fun hashCode(): Int = (xM.hashCode() * 31 + yM.hashCode()) * 31 + headingRad.hashCode()

    override fun toString(): String =
        "Pose(x=${round1(xM * 1000)} mm, y=${round1(yM * 1000)} mm, heading=${round(headingDeg * 100) / 100} deg)"

    private fun round1(v: Double): Double = round(v * 10) / 10

    public companion object {
        /** The origin, facing +x. */
        public val ORIGIN: Pose = Pose(0.0, 0.0, 0.0)

        /** A pose with its heading given in degrees. */
        public fun ofDegrees(xM: Double, yM: Double, headingDeg: Double): Pose = Pose(xM, yM, headingDeg * PI / 180.0)
    }
}

package org.pocketbot.sdk

import org.pocketbot.protocol.MoveArc
import org.pocketbot.protocol.MoveRotate
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.Packet

/** A movement the robot's firmware executes on its own with a smooth three-segment speed profile. */
public sealed class Movement {
    internal abstract fun toPacket(id: Int): Packet

    /**
     * Drive [distanceM] metres straight (negative: backwards) at a cruise speed of [speedMps] m/s (> 0).
     *
     * ```
     * Movement.Straight(distanceM = 0.10, speedMps = 0.2)   // 10 cm forward at 20 cm/s
     * ```
     */
    public data class Straight(public val distanceM: Double, public val speedMps: Double) : Movement() {
        init {
            require(speedMps > 0) { "speedMps must be > 0, was $speedMps" }
        }

        override fun toPacket(id: Int): Packet = MoveStraight(id, distanceM.toFloat(), speedMps.toFloat())
    }

    /** Rotate in place by [angleDeg] degrees (positive: left, counter-clockwise), wheels at [speedMps] m/s (> 0). */
    public data class Rotate(public val angleDeg: Double, public val speedMps: Double) : Movement() {
        init {
            require(speedMps > 0) { "speedMps must be > 0, was $speedMps" }
        }

        override fun toPacket(id: Int): Packet = MoveRotate(id, angleDeg.toFloat(), speedMps.toFloat())
    }

    /**
     * Move the robot centre along a circle of [radiusM] metres (> 0) through [angleDeg] degrees (positive: left
     * turn, negative: right turn) at a cruise speed of [speedMps] m/s (> 0).
     */
    public data class Arc(public val radiusM: Double, public val angleDeg: Double, public val speedMps: Double) : Movement() {
        init {
            require(radiusM > 0) { "radiusM must be > 0, was $radiusM" }
            require(speedMps > 0) { "speedMps must be > 0, was $speedMps" }
        }

        override fun toPacket(id: Int): Packet = MoveArc(id, radiusM.toFloat(), angleDeg.toFloat(), speedMps.toFloat())
    }
}

/** How a queued movement ended. */
public enum class MovementResult {
    /** The robot reported it finished. */
    FINISHED,

    /** [Locomotion.stop] cleared it from the queue before it finished (or the robot reset). */
    CANCELLED,
}

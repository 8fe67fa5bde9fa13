package org.pocketbot.sdk

import org.pocketbot.protocol.MoveArc
import org.pocketbot.protocol.MoveRotate
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.Packet

/**
 * A movement the robot's firmware executes on its own with a smooth three-segment speed profile. Each kind has a
 * main quantity in which [MovementResult.done] reports how much of it was done: metres for [Straight], degrees for
 * [Rotate] and [Arc].
 */
public sealed class Movement {
    internal abstract fun toPacket(id: Int): Packet

    /** The main quantity asked for, in [unit]. */
    public abstract val amount: Double

    /** The unit of [amount] and of [MovementResult.done]: metres or degrees. */
    public abstract val unit: MovementUnit

    /**
     * Drive [distanceM] metres straight (negative: backwards) at a cruise speed of [speedMps] m/s (> 0).
     *
     * ```
     * Movement.Straight(distanceM = 0.10, speedMps = 0.2)   // 10 cm forward at 20 cm/s
     * ```
     */
    public class Straight(public val distanceM: Double, public val speedMps: Double) : Movement() {
        init {
            require(distanceM.isFinite()) { "distanceM must be finite, was $distanceM" }
            require(speedMps > 0 && speedMps.isFinite()) { "speedMps must be > 0, was $speedMps" }
        }

        override val amount: Double get() = distanceM
        override val unit: MovementUnit get() = MovementUnit.METRE
        override fun toPacket(id: Int): Packet = MoveStraight(id, distanceM.toFloat(), speedMps.toFloat())
        override fun equals(other: Any?): Boolean = other is Straight && distanceM == other.distanceM && speedMps == other.speedMps
        override fun hashCode(): Int = distanceM.hashCode() * 31 + speedMps.hashCode()
        override fun toString(): String = "Straight(${distanceM} m at $speedMps m/s)"
    }

    /** Rotate in place by [angleDeg] degrees (positive: left, counter-clockwise), wheels at [speedMps] m/s (> 0). */
    public class Rotate(public val angleDeg: Double, public val speedMps: Double) : Movement() {
        init {
            require(angleDeg.isFinite()) { "angleDeg must be finite, was $angleDeg" }
            require(speedMps > 0 && speedMps.isFinite()) { "speedMps must be > 0, was $speedMps" }
        }

        override val amount: Double get() = angleDeg
        override val unit: MovementUnit get() = MovementUnit.DEGREE
        override fun toPacket(id: Int): Packet = MoveRotate(id, angleDeg.toFloat(), speedMps.toFloat())
        override fun equals(other: Any?): Boolean = other is Rotate && angleDeg == other.angleDeg && speedMps == other.speedMps
        override fun hashCode(): Int = angleDeg.hashCode() * 31 + speedMps.hashCode()
        override fun toString(): String = "Rotate($angleDeg deg at $speedMps m/s)"
    }

    /**
     * Move the robot centre along a circle of [radiusM] metres (> 0) through [angleDeg] degrees (positive: left
     * turn, negative: right turn) at a cruise speed of [speedMps] m/s (> 0).
     */
    public class Arc(public val radiusM: Double, public val angleDeg: Double, public val speedMps: Double) : Movement() {
        init {
            require(radiusM > 0 && radiusM.isFinite()) { "radiusM must be > 0, was $radiusM" }
            require(angleDeg.isFinite()) { "angleDeg must be finite, was $angleDeg" }
            require(speedMps > 0 && speedMps.isFinite()) { "speedMps must be > 0, was $speedMps" }
        }

        override val amount: Double get() = angleDeg
        override val unit: MovementUnit get() = MovementUnit.DEGREE
        override fun toPacket(id: Int): Packet = MoveArc(id, radiusM.toFloat(), angleDeg.toFloat(), speedMps.toFloat())
        override fun equals(other: Any?): Boolean =
            other is Arc && radiusM == other.radiusM && angleDeg == other.angleDeg && speedMps == other.speedMps

        override fun hashCode(): Int = (radiusM.hashCode() * 31 + angleDeg.hashCode()) * 31 + speedMps.hashCode()
        override fun toString(): String = "Arc(r=$radiusM m through $angleDeg deg at $speedMps m/s)"
    }
}

/** The unit of a movement's main quantity ([Movement.amount]) and of what was done of it ([MovementResult.done]). */
public enum class MovementUnit(
    /** As people write it after a number: `m`, `deg`. */
    public val symbol: String,
) {
    /** Metres: [Movement.Straight]. */
    METRE("m"),

    /** Degrees: [Movement.Rotate], [Movement.Arc]. */
    DEGREE("deg"),
    ;

    /** [symbol], so that `"$done ${movement.unit}"` reads `0.1 m`. */
    override fun toString(): String = symbol
}

/**
 * How a movement ended, as the robot reported it.
 *
 * @property outcome what ended it.
 * @property done how much of it was done, in the unit of the movement's main quantity ([Movement.unit], signed like
 *   [Movement.amount]), measured by the robot's encoders once it stood still; for [MovementOutcome.LOST], what this
 *   host saw of it in the encoder counts the robot reported (at least that much), or null when it never saw it run.
 * @property detail a sentence for people: what happened.
 */
public class MovementResult internal constructor(
    public val movement: Movement,
    public val outcome: MovementOutcome,
    public val done: Double?,
    public val detail: String,
) {
    override fun equals(other: Any?): Boolean =
        other is MovementResult && movement == other.movement && outcome == other.outcome && done == other.done

    override fun hashCode(): Int = (movement.hashCode() * 31 + outcome.hashCode()) * 31 + done.hashCode()

    override fun toString(): String =
        "$outcome${done?.let { " after ${round3(it)} ${movement.unit} of ${round3(movement.amount)}" } ?: ""}: $detail"
}

/** [v] to three decimals, for people (how much of a movement was done). */
internal fun round3(v: Double): String = (kotlin.math.round(v * 1000) / 1000).toString()

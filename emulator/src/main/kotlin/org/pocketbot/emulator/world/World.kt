package org.pocketbot.emulator.world

import kotlinx.serialization.SerialName
import kotlinx.serialization.Serializable
import org.pocketbot.sdk.Pose
import kotlinx.serialization.json.Json

/**
 * A world as stored in `emulator/worlds/<name>.json`: a floor with tape on it, boxes, and where robots start.
 * Lengths in metres, angles in degrees; x to the right, y up, heading 0 along +x, counter-clockwise positive.
 *
 * The floor has no walls: its size is what the panel draws and where [org.pocketbot.emulator.Emulator.addRobot] places
 * robots, but a robot may drive over its edge, where the floor reads white. Only boxes (and other robots) stop one.
 */
@Serializable
public class World(
    public val name: String,
    public val description: String = "",
    /** Floor size: the floor spans (0, 0) .. (widthM, heightM). */
    public val widthM: Double,
    public val heightM: Double,
    /** Ambient light seen by the line sensor's phototransistors, in ADC counts. */
    public val ambientAdc: Int = 300,
    /** Tape on the floor, painted in order: a later piece covers an earlier one. */
    public val tapes: List<Tape> = emptyList(),
    public val boxes: List<Box> = emptyList(),
    /** Start poses of the robots: [org.pocketbot.emulator.Emulator.addRobot] takes the first that is free. */
    public val starts: List<StartPose> = emptyList(),
) {
    public fun toJson(): String = json.encodeToString(serializer(), this)

    public companion object {
        internal val json: Json = Json { prettyPrint = true; ignoreUnknownKeys = false; encodeDefaults = true }

        public fun fromJson(text: String): World = json.decodeFromString(serializer(), text)
    }
}

/** A point on the floor, in metres. */
@Serializable
public class Point(public val x: Double, public val y: Double) {
    override fun equals(other: Any?): Boolean = other is Point && other.x == x && other.y == y
    override fun hashCode(): Int = 31 * x.hashCode() + y.hashCode()
    override fun toString(): String = "($x, $y)"
}

/**
 * Where a robot starts, as a world file writes it: the axle midpoint (`x`, `y` in metres) and the heading (`heading_deg`,
 * degrees counter-clockwise from +x). Everywhere else the emulator speaks [Pose], the SDK's pose type.
 */
@Serializable
public class StartPose(
    @SerialName("x") public val xM: Double,
    @SerialName("y") public val yM: Double,
    @SerialName("headingDeg") public val headingDeg: Double = 0.0,
) {
    /** This start as a [Pose]. */
    public fun toPose(): Pose = Pose.ofDegrees(xM, yM, headingDeg)

    override fun equals(other: Any?): Boolean =
        other is StartPose && other.xM == xM && other.yM == yM && other.headingDeg == headingDeg
    override fun hashCode(): Int = (31 * xM.hashCode() + yM.hashCode()) * 31 + headingDeg.hashCode()
    override fun toString(): String = "($xM m, $yM m, $headingDeg°)"
}

@Serializable
public enum class TapeColour(
    /** Darkness seen by the infrared line sensor: 0 white floor .. 1 black tape. */
    public val irDarkness: Double,
    /** What the colour sensor reads, 0..255 per channel. */
    public val r: Int, public val g: Int, public val b: Int,
) {
    @SerialName("white") WHITE(0.0, 235, 235, 235),
    @SerialName("black") BLACK(1.0, 18, 18, 20),
    @SerialName("red") RED(0.75, 200, 35, 40),
    @SerialName("blue") BLUE(0.85, 30, 60, 190),
    @SerialName("green") GREEN(0.8, 40, 170, 60),
}

/**
 * A strip of tape on the floor, [widthM] wide around its centre line. Its ends are round (a half disc of the
 * tape's width, as every piece of the floor model is a segment or arc with round ends), so a gap between two
 * tapes looks narrower than the gap between their end points by one tape width: a 15 mm gap between two 8 mm
 * tapes is about 7 mm of white floor.
 */
@Serializable
public sealed class Tape {
    public abstract val widthM: Double
    public abstract val colour: TapeColour

    /** Straight pieces through [points]; [closed] joins the last point back to the first. */
    @Serializable
    @SerialName("polyline")
    public class Polyline(
        public val points: List<Point>,
        override val widthM: Double = 0.008,
        override val colour: TapeColour = TapeColour.BLACK,
        public val closed: Boolean = false,
    ) : Tape()

    /** A circular arc of centre line radius [radiusM] from [startDeg] through [sweepDeg] (positive: counter-clockwise). */
    @Serializable
    @SerialName("arc")
    public class Arc(
        public val center: Point,
        public val radiusM: Double,
        public val startDeg: Double = 0.0,
        public val sweepDeg: Double = 360.0,
        override val widthM: Double = 0.008,
        override val colour: TapeColour = TapeColour.BLACK,
    ) : Tape()
}

/**
 * A box on the floor. A movable box slides when the robots pushing it overcome its Coulomb friction
 * (friction x mass x g); an immovable one is a wall.
 */
@Serializable
public class Box(
    public val center: Point,
    public val widthM: Double,
    public val heightM: Double,
    public val angleDeg: Double = 0.0,
    public val massKg: Double = 0.1,
    public val friction: Double = 0.25,
    public val movable: Boolean = true,
)

package org.pocketbot.emulator.world

import kotlinx.serialization.SerialName
import kotlinx.serialization.Serializable
import org.pocketbot.sdk.Pose
import kotlinx.serialization.json.Json

/**
 * A world as stored in `emulator/worlds/<name>.json`: a floor with tape on it, boxes, and where robots start.
 * Lengths in metres, angles in degrees; x to the right, y up, heading 0 along +x, counter-clockwise positive.
 */
@Serializable
public data class World(
    val name: String,
    val description: String = "",
    /** Floor size: the floor spans (0, 0) .. (widthM, heightM). */
    val widthM: Double,
    val heightM: Double,
    /** Ambient light seen by the line sensor's phototransistors, in ADC counts. */
    val ambientAdc: Int = 300,
    /** Tape on the floor, painted in order: a later piece covers an earlier one. */
    val tapes: List<Tape> = emptyList(),
    val boxes: List<Box> = emptyList(),
    /** Start poses of the robots, used in order by [org.pocketbot.emulator.Emulator.addRobot]. */
    val starts: List<StartPose> = emptyList(),
) {
    public fun toJson(): String = json.encodeToString(serializer(), this)

    public companion object {
        internal val json: Json = Json { prettyPrint = true; ignoreUnknownKeys = false; encodeDefaults = true }

        public fun fromJson(text: String): World = json.decodeFromString(serializer(), text)
    }
}

@Serializable
public data class Point(val x: Double, val y: Double)

/**
 * Where a robot starts, as a world file writes it: the axle midpoint (`x`, `y` in metres) and the heading (`heading_deg`,
 * degrees counter-clockwise from +x). Everywhere else the emulator speaks [Pose], the SDK's pose type.
 */
@Serializable
public data class StartPose(
    @SerialName("x") val xM: Double,
    @SerialName("y") val yM: Double,
    @SerialName("headingDeg") val headingDeg: Double = 0.0,
) {
    /** This start as a [Pose]. */
    public fun toPose(): Pose = Pose.ofDegrees(xM, yM, headingDeg)
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
    public data class Polyline(
        val points: List<Point>,
        override val widthM: Double = 0.008,
        override val colour: TapeColour = TapeColour.BLACK,
        val closed: Boolean = false,
    ) : Tape()

    /** A circular arc of centre line radius [radiusM] from [startDeg] through [sweepDeg] (positive: counter-clockwise). */
    @Serializable
    @SerialName("arc")
    public data class Arc(
        val center: Point,
        val radiusM: Double,
        val startDeg: Double = 0.0,
        val sweepDeg: Double = 360.0,
        override val widthM: Double = 0.008,
        override val colour: TapeColour = TapeColour.BLACK,
    ) : Tape()
}

/**
 * A box on the floor. A movable box slides when the robots pushing it overcome its Coulomb friction
 * (friction x mass x g); an immovable one is a wall.
 */
@Serializable
public data class Box(
    val center: Point,
    val widthM: Double,
    val heightM: Double,
    val angleDeg: Double = 0.0,
    val massKg: Double = 0.1,
    val friction: Double = 0.25,
    val movable: Boolean = true,
)

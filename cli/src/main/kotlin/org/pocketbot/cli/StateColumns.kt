package org.pocketbot.cli

import org.pocketbot.sdk.LineFlag
import org.pocketbot.sdk.LocoMode
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotState
import org.pocketbot.sdk.StateFields
import kotlin.math.round

/**
 * One column of `state`: a value of the robot's state (or of what the host derives from it, the odometry pose) by
 * name, and the most characters its text takes, so that a streamed table aligns.
 */
class StateColumn(val name: String, val width: Int, val of: (Robot, RobotState) -> Any?)

/** The columns `state` prints: a readable few by default, any state field or group, the pose, or all of them. */
object StateColumns {
    /**
     * The odometry pose, dead-reckoned by this host from the encoders since the command connected (the robot does not
     * know where it is): millimetres and tenths of a degree.
     */
    val pose = listOf(
        StateColumn("pose.x_m", 8) { r, _ -> round(r.odometry.pose.value.xM * 1000) / 1000 },
        StateColumn("pose.y_m", 8) { r, _ -> round(r.odometry.pose.value.yM * 1000) / 1000 },
        StateColumn("pose.heading_deg", 8) { r, _ -> round(Math.toDegrees(r.odometry.pose.value.headingRad) * 10) / 10 },
    )

    /** What `state` shows unless told otherwise: what people look at, in their units, one short line per robot. */
    val readable = listOf(
        StateColumn("time_s", 8) { _, s -> s.time.timeMs / 1000.0 },
        StateColumn("mode", LocoMode.entries.maxOf { it.name.length }) { _, s -> s.locomotion.mode },
        StateColumn("speed_mps", 6) { _, s -> (s.wheels.speedLeftMmps + s.wheels.speedRightMmps) / 2000.0 },
        StateColumn("line", 5) { _, s -> if (LineFlag.SEEN in s.line.flags) s.line.position else "none" },
        StateColumn("battery_v", 5) { _, s -> s.power.batteryMv / 1000.0 },
    ) + pose.map { StateColumn(it.name.removePrefix("pose."), it.width, it.of) }

    private val fields = StateFields.all.map { f -> StateColumn(f.name, f.width) { _, s -> f.of(s) } }

    /**
     * The columns called [names]: state fields or their groups (`wheels`), `pose` or one of its fields, or `all` (every
     * state field and the pose).
     * @throws IllegalArgumentException naming the first name that is none of these.
     */
    fun select(names: List<String>): List<StateColumn> = names.flatMap { n ->
        when {
            n == "all" -> fields + pose
            n == "pose" -> pose
            pose.any { it.name == n } -> pose.filter { it.name == n }
            else -> StateFields.select(listOf(n)).map { f -> fields.single { it.name == f.name } }
        }
    }
}

package org.pocketbot.android.model

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.SharingStarted
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.combine
import kotlinx.coroutines.flow.stateIn
import org.pocketbot.sdk.LineCalibration
import org.pocketbot.sdk.LineFlag
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotState

/** What the line sensor screen shows: each spot's reading and darkness, where the line is, whether it is seen. */
class LineSensorReading(
    /** Raw (ambient-suppressed) reading per spot, left to right, in ADC counts. */
    val raw: List<Int>,
    /** Darkness per spot with the robot's calibration, 0 white .. 1000 black. */
    val darkness: List<Int>,
    /** Line position, -1000 far left .. 1000 far right (permille). */
    val position: Int,
    val seen: Boolean,
    val lost: Boolean,
    /** The darkness above which a spot sees the line (settings.line_sensor.threshold). */
    val threshold: Int,
)

/** The line sensor, live: every state packet of the robot updates [reading]. */
class LineSensorModel(robot: Robot, scope: CoroutineScope) {
    val reading: StateFlow<LineSensorReading> = combine(robot.lineSensor.reading, robot.settings.values) { line, _ ->
        readingOf(line, LineCalibration.of(robot), robot.settings.lineSensor.threshold.value)
    }.stateIn(scope, SharingStarted.Eagerly, readingOf(robot.lineSensor.reading.value, LineCalibration.of(robot), robot.settings.lineSensor.threshold.value))

    private fun readingOf(line: RobotState.Line, calibration: LineCalibration, threshold: Int) = LineSensorReading(
        raw = line.raw,
        darkness = line.raw.mapIndexed { i, raw -> calibration.darknessPermille(i, raw) },
        position = line.position,
        seen = LineFlag.SEEN in line.flags,
        lost = LineFlag.LOST in line.flags,
        threshold = threshold,
    )
}

package org.pocketbot.android.model

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.SharingStarted
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.combine
import kotlinx.coroutines.flow.stateIn
import kotlinx.coroutines.flow.update
import org.pocketbot.sdk.Colour
import org.pocketbot.sdk.ColourMode
import org.pocketbot.sdk.DoubleSetting
import org.pocketbot.sdk.LineFollowStatus
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.SettingRefusedException

/** One speed setting as the screen shows it: the robot's value, and an edit waiting for its acknowledgement. */
data class SpeedSetting(val mps: Double, val pending: Boolean = false, val refused: String? = null)

/** What the line following screen shows. */
data class LineFollowView(
    val status: LineFollowStatus,
    val segment: Colour,
    /** Mean of the two measured wheel speeds, m/s. */
    val speedMps: Double,
    val colourMode: ColourMode,
    val speed: SpeedSetting,
    val redSpeed: SpeedSetting,
    val blueSpeed: SpeedSetting,
)

/**
 * Line following: start and stop, the colour mode (plain, or segments: red tape slows to the red speed, blue speeds up
 * to the blue speed) and the three speeds, which are the robot's settings line_follow.speed_mps, red_speed_mps and
 * blue_speed_mps, each written alone and acknowledged.
 */
class LineFollowModel(private val robot: Robot, scope: CoroutineScope, private val act: (String, suspend () -> Unit) -> Unit) {
    private val mode = MutableStateFlow(ColourMode.PLAIN)
    private val edits = MutableStateFlow<Map<String, SpeedSetting>>(emptyMap())
    private val settings = robot.settings.lineFollow

    val view: StateFlow<LineFollowView> = combine(robot.lineFollower.status, robot.motors.wheels, mode, edits, robot.settings.values) { status, wheels, m, e, _ ->
        LineFollowView(
            status = status.status,
            segment = status.segment,
            speedMps = (wheels.speedLeftMmps + wheels.speedRightMmps) / 2000.0,
            colourMode = m,
            speed = e[settings.speedMps.name] ?: SpeedSetting(settings.speedMps.value),
            redSpeed = e[settings.redSpeedMps.name] ?: SpeedSetting(settings.redSpeedMps.value),
            blueSpeed = e[settings.blueSpeedMps.name] ?: SpeedSetting(settings.blueSpeedMps.value),
        )
    }.stateIn(scope, SharingStarted.Eagerly, LineFollowView(
        LineFollowStatus.OFF, Colour.UNKNOWN, 0.0, ColourMode.PLAIN,
        SpeedSetting(settings.speedMps.value), SpeedSetting(settings.redSpeedMps.value), SpeedSetting(settings.blueSpeedMps.value),
    ))

    fun setColourMode(colourMode: ColourMode) {
        mode.value = colourMode
    }

    fun start() = act("start line following") { robot.lineFollower.start(colourMode = mode.value) }

    fun stop() = act("stop line following") { robot.lineFollower.stop() }

    fun setSpeed(mps: Double) = write(settings.speedMps, mps)
    fun setRedSpeed(mps: Double) = write(settings.redSpeedMps, mps)
    fun setBlueSpeed(mps: Double) = write(settings.blueSpeedMps, mps)

    /** Writes [setting]: pending until the robot acknowledges, then its value; or the robot's refusal. */
    private fun write(setting: DoubleSetting, mps: Double) {
        edits.update { it + (setting.name to SpeedSetting(mps, pending = true)) }
        act("set ${setting.name}") {
            try {
                setting.set(mps)
                edits.update { it - setting.name }
            } catch (e: SettingRefusedException) {
                edits.update { it + (setting.name to SpeedSetting(setting.value, refused = e.message)) }
            }
        }
    }
}

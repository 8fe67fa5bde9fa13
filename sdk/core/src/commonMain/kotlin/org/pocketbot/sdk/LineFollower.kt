package org.pocketbot.sdk

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.Colour
import org.pocketbot.protocol.ColourMode
import org.pocketbot.protocol.LineFollow
import org.pocketbot.protocol.LineFollowStatus
import org.pocketbot.protocol.StateLineFollow

/**
 * Line following in the firmware: a PD controller on the line position drives the wheel speeds. Tune it with
 * `robot.settings.linePid`; speeds are in `robot.settings.lineFollow`.
 */
public class LineFollower internal constructor(private val robot: Robot) {
    private val _status = MutableStateFlow(StateLineFollow(0, 0))

    /** Status (off, following, lost) and the colour of the segment under the robot (full state only). */
    public val status: StateFlow<StateLineFollow> = _status.asStateFlow()

    /** The follower's status, null for a code this SDK does not know. */
    public val followStatus: LineFollowStatus? get() = LineFollowStatus.fromCode(_status.value.status)

    /** The colour of the segment under the robot. */
    public val segment: Colour get() = Colour.fromCode(_status.value.segment) ?: Colour.UNKNOWN

    /**
     * Starts following the line at [speedMps] m/s (0: settings.line_follow.speed_mps); with
     * [ColourMode.SEGMENTS] red tape slows down and blue tape speeds up. Suspends until acknowledged.
     */
    public suspend fun start(speedMps: Double = 0.0, colourMode: ColourMode = ColourMode.PLAIN) {
        robot.command(LineFollow(1, colourMode.code, speedMps.toFloat()))
    }

    /** Stops following the line. */
    public suspend fun stop() {
        robot.command(LineFollow(0, ColourMode.PLAIN.code, 0f))
    }

    internal fun update(s: StateLineFollow) {
        _status.value = s
    }
}

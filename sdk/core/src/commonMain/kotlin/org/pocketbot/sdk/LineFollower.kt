package org.pocketbot.sdk

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.LineFollow
import org.pocketbot.sdk.internal.EMPTY_STATE
import org.pocketbot.sdk.internal.link.LinkPort

/**
 * Line following in the firmware: a PD controller on the line position drives the wheel speeds. Tune it with
 * `robot.settings.linePid`; speeds are in `robot.settings.lineFollow`. Line following goes on when the host link is
 * lost while settings.line_follow.autonomous is 1 (the default); otherwise the link failsafe stops it.
 */
public class LineFollower internal constructor(private val link: LinkPort) {
    private val _status = MutableStateFlow(EMPTY_STATE.lineFollow)

    /** Status (off, following, lost) and the colour of the segment under the robot (full state only). */
    public val status: StateFlow<RobotState.LineFollow> = _status.asStateFlow()

    /** The follower's status. */
    public val followStatus: LineFollowStatus get() = _status.value.status

    /** The colour of the segment under the robot. */
    public val segment: Colour get() = _status.value.segment

    /**
     * Starts following the line at [speedMps] m/s, or at settings.line_follow.speed_mps when null; with
     * [ColourMode.SEGMENTS] red tape slows down to settings.line_follow.red_speed_mps and blue tape speeds up to
     * settings.line_follow.blue_speed_mps. Clears the movement queue. Suspends until acknowledged.
     */
    public suspend fun start(speedMps: Double? = null, colourMode: ColourMode = ColourMode.PLAIN) {
        require(speedMps == null || (speedMps > 0 && speedMps.isFinite())) { "speedMps must be > 0, was $speedMps" }
        // On the wire 0 means "the speed from settings".
        link.command(LineFollow(1, colourMode.code, (speedMps ?: 0.0).toFloat()))
    }

    /** Stops following the line (and the motors). */
    public suspend fun stop() {
        link.command(LineFollow(0, ColourMode.PLAIN.code, 0f))
    }

    internal fun update(s: RobotState.LineFollow) {
        _status.value = s
    }
}

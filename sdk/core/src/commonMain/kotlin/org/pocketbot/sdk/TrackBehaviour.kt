package org.pocketbot.sdk

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.Track
import org.pocketbot.protocol.TrackAction
import org.pocketbot.sdk.internal.EMPTY_STATE
import org.pocketbot.sdk.internal.link.LinkPort

/**
 * Multiple robots on a track (thesis A.3): a behaviour that runs in the robot's own firmware, decentralized. The
 * host only starts, stops and reverses it and sets its speed; once started, the robots need no host at all.
 *
 * Each robot follows the line at `settings.track.speed_mps` and keeps its distance from the robot ahead by IR
 * proximity (half speed when it is close, waiting when it is very close). Robots that come close identify each
 * other by their IR beacons and greet each other with an IR message ([metId] names the robot met last). One robot
 * holds a token, created by the robot whose id is `settings.track.token_origin_id` at its first start; the holder
 * shows it ([holdsToken], the status LED `token`: the thesis's orange light) and drives
 * `settings.track.token_boost_percent` faster until it has caught up with the robot ahead and handed the token on
 * (an IR handshake by which at most one robot holds the token at any instant and it is never lost), so the token
 * travels round the track. An obstacle on the line is driven round on the right: the robot leaves the line, passes
 * it, finds the line again and lines up with it.
 *
 * **The link failsafe does not stop it**: the behaviour is the robot's own, not host-driven, so it goes on when the
 * host link is lost (as line following does with `settings.line_follow.autonomous` = 1). [stop], or any other
 * motion command (`locomotion.stop()`, a movement, teleoperation, line following), ends it.
 *
 * ```
 * for (robot in fleet.robots.value) robot.track.start()
 * fleet.robots.value.first().track.state.first { it.tokenVisits >= 2 }
 * for (robot in fleet.robots.value) robot.track.reverse()
 * ```
 * Safe to call from any thread and coroutine; the commands suspend until the robot acknowledged them.
 */
public class TrackBehaviour internal constructor(private val link: LinkPort, private val settings: RobotSettings) {
    private val _state = MutableStateFlow(EMPTY_STATE.track)

    /** What the behaviour does, whether this robot holds the token, its visits and the robot met last (full state only). */
    public val state: StateFlow<RobotState.Track> = _state.asStateFlow()

    /** What the behaviour is doing now ([TrackStatus.OFF] when it does not run). */
    public val status: TrackStatus get() = _state.value.status

    /** True while this robot holds the token. */
    public val holdsToken: Boolean get() = _state.value.token != 0

    /** How many times the token came to this robot from another one since the robot's reset. */
    public val tokenVisits: Int get() = _state.value.tokenVisits

    /** The id of the robot met last (heard close by IR and greeted), or 0. */
    public val metId: Int get() = _state.value.metId

    /** Starts the behaviour (ends a running movement, teleoperation or line following); starting it again while it runs changes nothing. */
    public suspend fun start() {
        link.command(Track(TrackAction.START.code))
    }

    /** Stops the behaviour and the motors. The token stays where it is. */
    public suspend fun stop() {
        link.command(Track(TrackAction.STOP.code))
    }

    /** Turns the robot round on the spot to go the other way along the line; it stays stopped if it was stopped. */
    public suspend fun reverse() {
        link.command(Track(TrackAction.REVERSE.code))
    }

    /**
     * Sets the cruise speed on the line, 0.03..0.3 m/s (`settings.track.speed_mps`), also while the behaviour runs.
     * @throws SettingRefusedException outside that range.
     */
    public suspend fun setSpeed(speedMps: Double) {
        settings.track.speedMps.set(speedMps)
    }

    internal fun update(s: RobotState.Track) {
        _state.value = s
    }
}

package org.pocketbot.sdk

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.SyncMode
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * State reflection (thesis 6.4, 9.7): what the robot sends on its own, and how often.
 *
 * - [SyncMode.FULL]: the whole `robot_state` (88 bytes) every period: every module of [Robot] updates.
 * - [SyncMode.REDUCED]: encoders, wheel speeds and line position (19 bytes), for fast charts and odometry; the rest
 *   of [Robot.state] keeps its last full value.
 * - [SyncMode.NONE]: nothing; the state stays as it was.
 *
 * ```
 * robot.reflector.set(SyncMode.REDUCED, period = 5.milliseconds)
 * ```
 * The choice survives reconnects (it is re-sent after each handshake).
 */
public class StateReflector internal constructor(private val robot: Robot) {
    private val _mode = MutableStateFlow(robot.options.syncMode)
    private val _period = MutableStateFlow(robot.options.syncPeriod)
    private var desiredMode = robot.options.syncMode
    private var desiredPeriod = robot.options.syncPeriod

    /** The sync mode the robot confirmed last. */
    public val mode: StateFlow<SyncMode> = _mode.asStateFlow()

    /** The period the robot confirmed last. */
    public val period: StateFlow<Duration> = _period.asStateFlow()

    /**
     * Asks the robot for [mode] every [period] (1 ms .. 60 s, whole milliseconds) and suspends until it acknowledged.
     * On a 115200-baud link a full state frame takes about 8 ms, a reduced one about 2.3 ms: shorter periods than
     * that are sent as fast as the link allows.
     */
    public suspend fun set(mode: SyncMode, period: Duration = this.period.value) {
        require(period in 1.milliseconds..60.seconds) { "period $period is outside 1 ms .. 60 s" }
        val previous = robot.serial {
            val before = desiredMode to desiredPeriod
            desiredMode = mode
            desiredPeriod = period
            before
        }
        try {
            robot.command(desiredPacket())
        } catch (e: Throwable) {
            robot.serial {
                desiredMode = previous.first
                desiredPeriod = previous.second
            }
            throw e
        }
        robot.serial { confirmed() }
    }

    internal fun desiredPacket(): SetSync = SetSync(desiredMode.code, desiredPeriod.inWholeMilliseconds.toInt())

    internal suspend fun confirmed() {
        _mode.value = desiredMode
        _period.value = desiredPeriod
        val p = desiredPacket()
        val bytes = byteArrayOf(p.mode.toByte(), p.periodMs.toByte(), (p.periodMs shr 8).toByte())
        val at = robot.settings.sync.mode.info.offset
        if (robot.settingsBytes.copyOfRange(at, at + 3).contentEquals(bytes).not()) robot.settingsWritten(at, bytes)
    }
}

package org.pocketbot.sdk

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.SetSync
import org.pocketbot.sdk.internal.SettingsMirror
import org.pocketbot.sdk.internal.link.LinkPort
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * State reflection (thesis 6.4, 9.7): what the robot sends on its own, and how often.
 *
 * - [SyncMode.FULL]: the whole `robot_state` (88 bytes) every period: every module of [Robot] updates.
 * - [SyncMode.REDUCED]: encoders, wheel speeds and line position (19 bytes), for fast charts and odometry; the rest
 *   of [Robot.state] keeps its last full value.
 * - [SyncMode.NONE]: nothing; the state stays as it was, and the SDK stops watching the link for silence.
 *
 * ```
 * robot.reflector.set(SyncMode.REDUCED, period = 5.milliseconds)
 * ```
 * The reflector is the one owner of the sync mode and period: writing `robot.settings.sync.mode` or `.periodMs`, or
 * loading the defaults, changes it too. The choice survives reconnects and robot resets (it is sent again after
 * each handshake). Every host connected to a robot gets the same state: the driver chooses it; a host that watches
 * takes the robot's mode and period as they are ([set] is the driver's).
 */
public class StateReflector internal constructor(private val link: LinkPort, private val mirror: SettingsMirror) {
    private val _mode = MutableStateFlow(link.options.syncMode)
    private val _period = MutableStateFlow(link.options.syncPeriod)
    private var desiredMode = link.options.syncMode
    private var desiredPeriod = link.options.syncPeriod

    /** The sync mode the robot confirmed last. */
    public val mode: StateFlow<SyncMode> = _mode.asStateFlow()

    /** The period the robot confirmed last. */
    public val period: StateFlow<Duration> = _period.asStateFlow()

    init {
        mirror.onUserChange = { offset, data -> adopt(offset, data) }
    }

    /**
     * Asks the robot for [mode] every [period] (1 ms .. 60 s, whole milliseconds) and suspends until it acknowledged.
     * On a 115200-baud link a full state frame takes about 8 ms, a reduced one about 2.3 ms: shorter periods than
     * that are sent as fast as the link allows.
     */
    public suspend fun set(mode: SyncMode, period: Duration = this.period.value) {
        require(period in 1.milliseconds..60.seconds) { "period $period is outside 1 ms .. 60 s" }
        require(mode.code >= 0) { "$mode is no sync mode" }
        link.command(SetSync(mode.code, period.inWholeMilliseconds.toInt()))
        link.serial { confirm(mode, period) }
    }

    /** After a handshake: the robot gets the mode it should have. */
    internal suspend fun restore(exchange: suspend (Packet) -> Unit) {
        exchange(SetSync(desiredMode.code, desiredPeriod.inWholeMilliseconds.toInt()))
        confirm(desiredMode, desiredPeriod)
    }

    /** After a handshake of a host that watches: the robot runs the mode its settings say (the driver's choice). */
    internal fun adoptRobots() {
        val sync = mirror.values.value.sync
        val mode = SyncMode.entries.firstOrNull { it.code == sync.mode } ?: return
        adopted(mode, sync.periodMs.milliseconds)
    }

    /** The robot runs [mode] every [period] now, and keeps them in settings.sync: the mirror says so too. */
    private suspend fun confirm(mode: SyncMode, period: Duration) {
        adopted(mode, period)
        val ms = period.inWholeMilliseconds.toInt()
        mirror.confirmed(MODE_OFFSET, byteArrayOf(mode.code.toByte()))
        mirror.confirmed(PERIOD_OFFSET, byteArrayOf(ms.toByte(), (ms shr 8).toByte()))
    }

    private fun adopted(mode: SyncMode, period: Duration) {
        desiredMode = mode
        desiredPeriod = period
        _mode.value = mode
        _period.value = period
    }

    /** A confirmed change of the settings that touches settings.sync: the robot now runs what they say. */
    private fun adopt(offset: Int, data: ByteArray) {
        val end = offset + data.size
        fun byte(at: Int): Int? = if (at in offset until end) data[at - offset].toInt() and 0xFF else null
        val mode = byte(MODE_OFFSET)?.let { code -> SyncMode.entries.firstOrNull { it.code == code } }
        val lo = byte(PERIOD_OFFSET)
        val hi = byte(PERIOD_OFFSET + 1)
        val period = if (lo != null && hi != null) (lo or (hi shl 8)).milliseconds else null
        if (mode != null || period != null) adopted(mode ?: desiredMode, period ?: desiredPeriod)
    }

    private companion object {
        val MODE_OFFSET = SETTINGS_FIELDS.single { it.path == "sync.mode" }.offset
        val PERIOD_OFFSET = SETTINGS_FIELDS.single { it.path == "sync.period_ms" }.offset
    }
}

package org.pocketbot.sdk

import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.sdk.internal.link.LinkPort
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.TimeMark
import kotlin.time.TimeSource

/** Why values of [Robot.state] are not live. */
public enum class StaleReason {
    /** No state that carries them has arrived since the link came up. */
    NOT_YET,

    /** The link is down (lost, reconnecting or closed): nothing the robot measures reaches this host. */
    LINK_DOWN,

    /**
     * The sync mode does not carry them: reduced state (while a controller is tuned) carries robot time, encoders,
     * wheel speeds and the line position only; sync mode none carries nothing.
     */
    NOT_SENT,

    /** The link is up and the sync mode carries them, but the robot has sent none for several periods. */
    SILENT,
}

/**
 * Whether some values of [Robot.state] are live, and if not, why and since when: a face shows a value that is not
 * live greyed, with its age, never as if it were current.
 *
 * @property staleBecause why the values are not live; null while they are.
 * @property heardAt when they last arrived, on this host's monotonic clock ([TimeSource.Monotonic]); null while they
 *   are live, or when none ever arrived.
 * @property robotTimeMs the robot time (ms since its reset) they were measured at, with the same nulls.
 */
public class Freshness internal constructor(
    public val staleBecause: StaleReason?,
    public val heardAt: TimeMark?,
    public val robotTimeMs: Long?,
) {
    /** True while the values are current. */
    public val isLive: Boolean get() = staleBecause == null

    /** How long ago the values arrived, or null while they are live or when none ever did. */
    public fun age(): Duration? = heardAt?.elapsedNow()

    override fun equals(other: Any?): Boolean =
        other is Freshness && staleBecause == other.staleBecause && heardAt == other.heardAt && robotTimeMs == other.robotTimeMs

    override fun hashCode(): Int = (staleBecause.hashCode() * 31 + heardAt.hashCode()) * 31 + robotTimeMs.hashCode()

    override fun toString(): String = if (isLive) "live" else "stale ($staleBecause, robot time $robotTimeMs ms)"

    internal companion object {
        val LIVE = Freshness(null, null, null)
    }
}

/**
 * How current the values of [Robot.state] are, in the two groups the robot sends them in.
 *
 * @property full every value, including those only full states carry (locomotion, battery, proximity, colour,
 *   accelerometer, track, error counters, the line sensor's spots).
 * @property reduced what reduced states carry too: robot time, encoders, wheel speeds, the line position
 *   (and what the host derives from them, such as the odometry pose). Never less live than [full].
 */
public class StateFreshness internal constructor(public val full: Freshness, public val reduced: Freshness) {
    override fun equals(other: Any?): Boolean = other is StateFreshness && full == other.full && reduced == other.reduced
    override fun hashCode(): Int = full.hashCode() * 31 + reduced.hashCode()
    override fun toString(): String = "StateFreshness(full $full, reduced $reduced)"
}

/**
 * Keeps [Robot.freshness]: told of every state update and of every change of the link and the sync mode, and wakes
 * now and then to notice a robot that went quiet. Everything runs on the link's serial context; the quiet test uses
 * coroutine delays only, so it follows the dispatcher's clock (simulated time too).
 */
internal class FreshnessWatch(private val link: LinkPort, private val reflector: StateReflector) {
    /** One group of values: when it was last heard, and whether since the link came up and since the last wake. */
    private class Group {
        var heardAt: TimeMark? = null
        var robotTimeMs: Long? = null
        var sinceLinkUp = false
        var sinceWake = false
        var quietWakes = 0
    }

    private val full = Group()
    private val any = Group()
    private var connected = false
    private val _freshness = MutableStateFlow(StateFreshness(stale(full, StaleReason.NOT_YET), stale(any, StaleReason.NOT_YET)))
    val freshness: StateFlow<StateFreshness> = _freshness.asStateFlow()

    /** Starts following the link and the sync mode; ends with the robot. */
    fun start(connection: StateFlow<ConnectionState>) {
        link.launch {
            connection.collect { c ->
                connected = c == ConnectionState.Connected
                if (!connected) listOf(full, any).forEach { it.sinceLinkUp = false }
                publish()
            }
        }
        link.launch { reflector.mode.collect { publish() } }
        link.launch {
            while (true) {
                // Quiet for two wakes in a row, at least the window long: silent.
                delay(window() / 2)
                for (g in listOf(full, any)) {
                    g.quietWakes = if (g.sinceWake) 0 else g.quietWakes + 1
                    g.sinceWake = false
                }
                publish()
            }
        }
    }

    /** A state update arrived ([isFull]: a full one), measured at robot time [timeMs]. */
    fun heard(isFull: Boolean, timeMs: Long) {
        val now = TimeSource.Monotonic.markNow()
        for (g in if (isFull) listOf(full, any) else listOf(any)) {
            g.heardAt = now
            g.robotTimeMs = timeMs
            g.sinceLinkUp = true
            g.sinceWake = true
            g.quietWakes = 0
        }
        val f = _freshness.value
        if (!f.reduced.isLive || (isFull && !f.full.isLive)) publish()
    }

    private fun window(): Duration = maxOf(reflector.period.value * 3, MIN_WINDOW)

    private fun publish() {
        val mode = reflector.mode.value
        _freshness.value = StateFreshness(
            freshness(full, carried = mode == SyncMode.FULL),
            freshness(any, carried = mode == SyncMode.FULL || mode == SyncMode.REDUCED),
        )
    }

    private fun freshness(g: Group, carried: Boolean): Freshness = when {
        !connected -> stale(g, StaleReason.LINK_DOWN)
        !carried -> stale(g, StaleReason.NOT_SENT)
        !g.sinceLinkUp -> stale(g, StaleReason.NOT_YET)
        g.quietWakes >= 2 -> stale(g, StaleReason.SILENT)
        else -> Freshness.LIVE
    }

    private fun stale(g: Group, why: StaleReason) = Freshness(why, g.heardAt, g.robotTimeMs)

    private companion object {
        /** The shortest quiet time called silence: a few lost frames on a busy radio are not. */
        val MIN_WINDOW = 500.milliseconds
    }
}

package org.pocketbot.sdk

import org.pocketbot.protocol.SyncMode
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * How a [Robot] talks to its robot. The defaults suit a Bluetooth or 115200-baud serial link.
 *
 * @property syncMode state reflection mode requested at connect (and re-sent after every reconnect).
 * @property syncPeriod state period requested at connect, 1 ms .. 60 s.
 * @property helloTimeout how long to wait for `hello` after each `hello_request`.
 * @property helloAttempts how many `hello_request`s before the connect fails.
 * @property commandTimeout how long to wait for the ack of an acknowledged command before sending it again
 *   (with the same sequence number, so the robot never executes it twice).
 * @property commandRetries retransmissions on a live link before [CommandTimeoutException].
 * @property settingsReadTimeout how long a whole `read_settings` answer may take.
 * @property silenceTimeout while the robot is asked to send state, no frame for this long means the link is lost.
 * @property heartbeatPeriod the longest quiet time before a `heartbeat`; null = a third of
 *   settings.link.failsafe_timeout_ms (at most 1 s), so the robot's failsafe never stops host-driven motion while
 *   the link is up.
 * @property reconnect backoff after a link loss.
 * @property settingsCache where learned settings are kept, by the robot's address and layout; an entry is used only
 *   when the robot's `hello` reports the same settings checksum, so a robot whose settings changed elsewhere is read
 *   again. null reads on every connect.
 * @property role drive (if no other host does), watch, or take the robot over ([Role]); asked at the connect and, as
 *   [Role.DRIVE] after a take-over, at every reconnect.
 * @property hostLabel who this host is, for the people at other hosts: `<program>@<computer>`, e.g. `panel@lab-pc`
 *   (the robot keeps 16 bytes of it). On the JVM `HostLabel.of("panel")` makes one.
 */
public class RobotOptions(
    public val syncMode: SyncMode = SyncMode.FULL,
    public val syncPeriod: Duration = 100.milliseconds,
    public val helloTimeout: Duration = 500.milliseconds,
    public val helloAttempts: Int = 4,
    public val commandTimeout: Duration = 250.milliseconds,
    public val commandRetries: Int = 8,
    public val settingsReadTimeout: Duration = 1.seconds,
    public val silenceTimeout: Duration = 2.seconds,
    public val heartbeatPeriod: Duration? = null,
    public val reconnect: ReconnectPolicy = ReconnectPolicy(),
    public val settingsCache: SettingsCache? = SettingsCache.shared,
    public val role: Role = Role.DRIVE,
    public val hostLabel: String = "pocketbot-sdk",
) {
    init {
        require(syncPeriod in 1.milliseconds..60.seconds) { "syncPeriod $syncPeriod is outside 1 ms .. 60 s" }
        require(helloAttempts >= 1) { "helloAttempts must be at least 1" }
        require(commandRetries >= 0) { "commandRetries must not be negative" }
    }

    /** A copy with some options changed. */
    public fun copy(
        syncMode: SyncMode = this.syncMode,
        syncPeriod: Duration = this.syncPeriod,
        helloTimeout: Duration = this.helloTimeout,
        helloAttempts: Int = this.helloAttempts,
        commandTimeout: Duration = this.commandTimeout,
        commandRetries: Int = this.commandRetries,
        settingsReadTimeout: Duration = this.settingsReadTimeout,
        silenceTimeout: Duration = this.silenceTimeout,
        heartbeatPeriod: Duration? = this.heartbeatPeriod,
        reconnect: ReconnectPolicy = this.reconnect,
        settingsCache: SettingsCache? = this.settingsCache,
        role: Role = this.role,
        hostLabel: String = this.hostLabel,
    ): RobotOptions = RobotOptions(
        syncMode, syncPeriod, helloTimeout, helloAttempts, commandTimeout, commandRetries, settingsReadTimeout,
        silenceTimeout, heartbeatPeriod, reconnect, settingsCache, role, hostLabel,
    )
}

/**
 * When to try again after a link loss: every [initialDelay] for the first [quickFor] (while the robot's failsafe,
 * 1 s by default, has not stopped it yet, a link that comes back is found within [initialDelay]), then with a delay
 * growing by [factor] up to [maxDelay]; after [maxAttempts] failed attempts in a row the robot is closed. A failed
 * attempt on a link that is down costs little (a refused socket, an absent tty).
 */
public class ReconnectPolicy(
    public val initialDelay: Duration = 25.milliseconds,
    public val maxDelay: Duration = 1.seconds,
    public val factor: Double = 2.0,
    public val maxAttempts: Int = Int.MAX_VALUE,
    public val quickFor: Duration = 2.seconds,
) {
    init {
        require(!initialDelay.isNegative() && maxDelay >= initialDelay) { "need 0 <= initialDelay <= maxDelay" }
        require(factor >= 1.0) { "factor must be at least 1" }
        require(maxAttempts >= 1) { "maxAttempts must be at least 1" }
        require(!quickFor.isNegative()) { "quickFor must not be negative" }
    }

    /** The wait before the next attempt, [since] the loss, when the wait before the last one was [last] (null: none yet). */
    internal fun nextDelay(since: Duration, last: Duration?): Duration =
        if (since < quickFor || last == null) initialDelay else minOf(maxDelay, maxOf(last, initialDelay) * factor)
}

package org.pocketbot.sdk

import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * How a [Robot] talks to its robot, made by a builder so that a new option never breaks a caller:
 *
 * ```
 * val options = RobotOptions {
 *     syncPeriod = 50.milliseconds
 *     reconnect { maxAttempts = 10 }
 * }
 * val watcher = RobotOptions(options) { role = Role.WATCH } // the same, but watching
 * ```
 *
 * The defaults ([RobotOptions.Builder]'s initial values) suit a Bluetooth or 115200-baud serial link. Immutable.
 */
public class RobotOptions private constructor(b: Builder) {
    /** State reflection mode requested at connect (and re-sent after every reconnect). */
    public val syncMode: SyncMode = b.syncMode

    /** State period requested at connect, 1 ms .. 60 s. */
    public val syncPeriod: Duration = b.syncPeriod

    /** How long to wait for `hello` after each `hello_request`. */
    public val helloTimeout: Duration = b.helloTimeout

    /** How many `hello_request`s before the connect fails. */
    public val helloAttempts: Int = b.helloAttempts

    /**
     * How long to wait for the ack of an acknowledged command before sending it again (with the same sequence
     * number, so the robot never executes it twice).
     */
    public val commandTimeout: Duration = b.commandTimeout

    /** Retransmissions on a live link before [CommandTimeoutException]. */
    public val commandRetries: Int = b.commandRetries

    /** How long a whole `read_settings` answer may take. */
    public val settingsReadTimeout: Duration = b.settingsReadTimeout

    /** While the robot is asked to send state, no frame for this long means the link is lost. */
    public val silenceTimeout: Duration = b.silenceTimeout

    /**
     * The longest quiet time before a `heartbeat`; null = a third of settings.link.failsafe_timeout_ms (at most
     * 1 s), so the robot's failsafe never stops host-driven motion while the link is up.
     */
    public val heartbeatPeriod: Duration? = b.heartbeatPeriod

    /** Backoff after a link loss. */
    public val reconnect: ReconnectPolicy = b.reconnect

    /**
     * Where learned settings are kept, by the robot's address and layout; an entry is used only when the robot's
     * `hello` reports the same settings checksum, so a robot whose settings changed elsewhere is read again. null
     * reads on every connect.
     */
    public val settingsCache: SettingsCache? = b.settingsCache

    /**
     * Drive (if no other host does), watch, or take the robot over ([Role]); asked at the connect and, as
     * [Role.DRIVE] after a take-over, at every reconnect.
     */
    public val role: Role = b.role

    /**
     * Who this host is, for the people at other hosts: `<program>@<computer>`, e.g. `panel@lab-pc` (the robot keeps
     * 16 bytes of it). On the JVM `HostLabel.of("panel")` makes one.
     */
    public val hostLabel: String = b.hostLabel

    init {
        require(syncPeriod in 1.milliseconds..60.seconds) { "syncPeriod $syncPeriod is outside 1 ms .. 60 s" }
        require(helloAttempts >= 1) { "helloAttempts must be at least 1" }
        require(commandRetries >= 0) { "commandRetries must not be negative" }
    }

    /**
     * The options being made by [RobotOptions] `{ ... }`: each property (documented on [RobotOptions] under the same
     * name) starts at its default, or at the value of the options it was made `from`. Checked when the block ends.
     */
    @OptionsDsl
    public class Builder internal constructor(from: RobotOptions?) {
        public var syncMode: SyncMode = from?.syncMode ?: SyncMode.FULL
        public var syncPeriod: Duration = from?.syncPeriod ?: 100.milliseconds
        public var helloTimeout: Duration = from?.helloTimeout ?: 500.milliseconds
        public var helloAttempts: Int = from?.helloAttempts ?: 4
        public var commandTimeout: Duration = from?.commandTimeout ?: 250.milliseconds
        public var commandRetries: Int = from?.commandRetries ?: 8
        public var settingsReadTimeout: Duration = from?.settingsReadTimeout ?: 1.seconds
        public var silenceTimeout: Duration = from?.silenceTimeout ?: 2.seconds
        public var heartbeatPeriod: Duration? = from?.heartbeatPeriod
        public var reconnect: ReconnectPolicy = from?.reconnect ?: ReconnectPolicy()
        public var settingsCache: SettingsCache? = if (from != null) from.settingsCache else SettingsCache.shared
        public var role: Role = from?.role ?: Role.DRIVE
        public var hostLabel: String = from?.hostLabel ?: "pocketbot-sdk"

        /** Changes [reconnect]: `reconnect { maxAttempts = 10 }`. */
        public fun reconnect(configure: ReconnectPolicy.Builder.() -> Unit) {
            reconnect = ReconnectPolicy(reconnect, configure)
        }

        internal fun build(): RobotOptions = RobotOptions(this)
    }
}

/** Options made by [configure] from the defaults: `RobotOptions { hostLabel = "panel@lab-pc" }`. */
public fun RobotOptions(configure: RobotOptions.Builder.() -> Unit = {}): RobotOptions =
    RobotOptions.Builder(null).apply(configure).build()

/** Options made by [configure] from [from]'s values: `RobotOptions(options) { role = Role.WATCH }`. */
public fun RobotOptions(from: RobotOptions, configure: RobotOptions.Builder.() -> Unit): RobotOptions =
    RobotOptions.Builder(from).apply(configure).build()

/**
 * When to try again after a link loss: every [initialDelay] for the first [quickFor] (while the robot's failsafe,
 * 1 s by default, has not stopped it yet, a link that comes back is found within [initialDelay]), then with a delay
 * growing by [factor] up to [maxDelay]; after [maxAttempts] failed attempts in a row the robot is closed. A failed
 * attempt on a link that is down costs little (a refused socket, an absent tty). Made by a builder:
 * `ReconnectPolicy { maxAttempts = 10 }`, or inside options: `RobotOptions { reconnect { maxAttempts = 10 } }`.
 */
public class ReconnectPolicy private constructor(b: Builder) {
    /** The wait before each attempt while [quickFor] has not passed, and the first wait after it. */
    public val initialDelay: Duration = b.initialDelay

    /** The longest wait between attempts. */
    public val maxDelay: Duration = b.maxDelay

    /** How much each wait grows after [quickFor]. */
    public val factor: Double = b.factor

    /** Failed attempts in a row after which the robot is closed. */
    public val maxAttempts: Int = b.maxAttempts

    /** How long after the loss the attempts come every [initialDelay]. */
    public val quickFor: Duration = b.quickFor

    init {
        require(!initialDelay.isNegative() && maxDelay >= initialDelay) { "need 0 <= initialDelay <= maxDelay" }
        require(factor >= 1.0) { "factor must be at least 1" }
        require(maxAttempts >= 1) { "maxAttempts must be at least 1" }
        require(!quickFor.isNegative()) { "quickFor must not be negative" }
    }

    /** The wait before the next attempt, [since] the loss, when the wait before the last one was [last] (null: none yet). */
    internal fun nextDelay(since: Duration, last: Duration?): Duration =
        if (since < quickFor || last == null) initialDelay else minOf(maxDelay, maxOf(last, initialDelay) * factor)

    /**
     * The policy being made by [ReconnectPolicy] `{ ... }`: each property (documented on [ReconnectPolicy] under the
     * same name) starts at its default, or at the value of the policy it was made `from`. Checked when the block ends.
     */
    @OptionsDsl
    public class Builder internal constructor(from: ReconnectPolicy?) {
        public var initialDelay: Duration = from?.initialDelay ?: 25.milliseconds
        public var maxDelay: Duration = from?.maxDelay ?: 1.seconds
        public var factor: Double = from?.factor ?: 2.0
        public var maxAttempts: Int = from?.maxAttempts ?: Int.MAX_VALUE
        public var quickFor: Duration = from?.quickFor ?: 2.seconds

        internal fun build(): ReconnectPolicy = ReconnectPolicy(this)
    }
}

/** A policy made by [configure] from the defaults: `ReconnectPolicy { maxAttempts = 3 }`. */
public fun ReconnectPolicy(configure: ReconnectPolicy.Builder.() -> Unit = {}): ReconnectPolicy =
    ReconnectPolicy.Builder(null).apply(configure).build()

/** A policy made by [configure] from [from]'s values. */
public fun ReconnectPolicy(from: ReconnectPolicy, configure: ReconnectPolicy.Builder.() -> Unit): ReconnectPolicy =
    ReconnectPolicy.Builder(from).apply(configure).build()

/** Keeps an outer builder's properties out of an inner builder's block (`reconnect { role = ... }` does not compile). */
@DslMarker
internal annotation class OptionsDsl

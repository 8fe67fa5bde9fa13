package org.pocketbot.sdk

/**
 * Where the link to one robot stands. Its states are classes, not data classes, so that a later field does not
 * break callers: compare them with `==` or `is`, read their properties by name. [Robot.connection] moves through
 * `Connecting -> Connected -> Lost -> Reconnecting -> Connected ... -> Closed`.
 */
public sealed class ConnectionState {
    /** The first link is being opened and the handshake is running. */
    public data object Connecting : ConnectionState()

    /** The link is up, the handshake passed, commands flow. */
    public data object Connected : ConnectionState()

    /**
     * The link broke ([reason] says how); set the moment it is noticed. The SDK waits out its backoff and then
     * moves to [Reconnecting]. Commands issued now wait for the new link; none is lost. While the link is down the
     * robot's own link failsafe may stop it (see [Locomotion]).
     */
    public class Lost(public val reason: String) : ConnectionState() {
        override fun equals(other: Any?): Boolean = other is Lost && reason == other.reason
        override fun hashCode(): Int = reason.hashCode()
        override fun toString(): String = "Lost(reason=$reason)"
    }

    /** Attempt number [attempt] (from 1) to open a new link and repeat the handshake is running. */
    public class Reconnecting(public val attempt: Int) : ConnectionState() {
        override fun equals(other: Any?): Boolean = other is Reconnecting && attempt == other.attempt
        override fun hashCode(): Int = attempt
        override fun toString(): String = "Reconnecting(attempt=$attempt)"
    }

    /** The robot was closed by [Robot.close] ([cause] null) or given up on ([cause] says why). Final. */
    public class Closed(public val cause: Throwable?) : ConnectionState() {
        override fun equals(other: Any?): Boolean = other is Closed && cause == other.cause
        override fun hashCode(): Int = cause?.hashCode() ?: 0
        override fun toString(): String = "Closed(cause=$cause)"
    }
}

/**
 * One step of [Robot.connection], as [Robot.connectionChanges] reports it.
 *
 * @property number counts the steps of this robot from 1 without gaps: a collector that sees a gap knows it fell
 *   more than the buffer behind.
 * @property state the state entered.
 */
public class ConnectionChange(public val number: Long, public val state: ConnectionState) {
    override fun equals(other: Any?): Boolean = other is ConnectionChange && number == other.number && state == other.state
    override fun hashCode(): Int = number.hashCode() * 31 + state.hashCode()
    override fun toString(): String = "#$number $state"
}

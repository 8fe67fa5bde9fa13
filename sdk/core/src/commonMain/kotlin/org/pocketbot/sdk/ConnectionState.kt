package org.pocketbot.sdk

/**
 * Where the link to one robot stands. [Robot.connection] moves through
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
    public data class Lost(public val reason: String) : ConnectionState()

    /** Attempt number [attempt] (from 1) to open a new link and repeat the handshake is running. */
    public data class Reconnecting(public val attempt: Int) : ConnectionState()

    /** The robot was closed by [Robot.close] ([cause] null) or given up on ([cause] says why). Final. */
    public data class Closed(public val cause: Throwable?) : ConnectionState()
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

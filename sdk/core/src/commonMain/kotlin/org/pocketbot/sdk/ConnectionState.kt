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
     * moves to [Reconnecting]. Commands issued now wait for the new link; none is lost.
     */
    public data class Lost(public val reason: String) : ConnectionState()

    /** Attempt number [attempt] (from 1) to open a new link and repeat the handshake is running. */
    public data class Reconnecting(public val attempt: Int) : ConnectionState()

    /** The robot was closed by [Robot.close] ([cause] null) or given up on ([cause] says why). Final. */
    public data class Closed(public val cause: Throwable?) : ConnectionState()
}

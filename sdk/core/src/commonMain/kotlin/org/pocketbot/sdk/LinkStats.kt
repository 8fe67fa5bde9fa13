package org.pocketbot.sdk

/**
 * Counters of one robot's link since [Robot] was created; see [Robot.linkStats]. Every frame that is dropped is
 * counted here once, logged to [DebugLog], and never touches the robot's state.
 *
 * @property framesReceived frames handed over by the transport, valid or not.
 * @property framesSent frames sent, retransmissions and heartbeats included.
 * @property fullStates `state_full` packets applied.
 * @property reducedStates `state_reduced` packets applied.
 * @property badCrc frames dropped because the CRC did not match (corrupted on the way).
 * @property badLength frames dropped because their length disagreed with the frame or the packet type (truncated).
 * @property tooShort frames shorter than a header and a CRC.
 * @property tooLong frames longer than the protocol allows.
 * @property unknownType frames of a packet type this SDK does not know.
 * @property unexpected valid packets that make no sense here (host-to-robot types, settings data nobody asked for).
 * @property strayAcks acks and errors for no command in flight (late answers to a retransmitted command).
 * @property retransmissions commands sent again with the same sequence number after a timeout or reconnect.
 * @property refused commands the robot refused with an `error` packet.
 * @property robotErrors `error` packets about frames the robot dropped (it saw our bytes damaged).
 * @property reconnects links re-established after a loss.
 */
public data class LinkStats(
    public val framesReceived: Long = 0,
    public val framesSent: Long = 0,
    public val fullStates: Long = 0,
    public val reducedStates: Long = 0,
    public val badCrc: Long = 0,
    public val badLength: Long = 0,
    public val tooShort: Long = 0,
    public val tooLong: Long = 0,
    public val unknownType: Long = 0,
    public val unexpected: Long = 0,
    public val strayAcks: Long = 0,
    public val retransmissions: Long = 0,
    public val refused: Long = 0,
    public val robotErrors: Long = 0,
    public val reconnects: Long = 0,
) {
    /** Frames dropped as corrupt, truncated or unknown. */
    public val dropped: Long get() = badCrc + badLength + tooShort + tooLong + unknownType
}

package org.pocketbot.sdk

/**
 * Counters of one robot's link since [Robot] was created; see [Robot.linkStats]. Every frame that is dropped, by
 * the transport's SLIP decoder or by the frame decoder, is counted here once, logged to [DebugLog], and never
 * touches the robot's state.
 *
 * @property framesReceived frames handed over by the transport, valid or not.
 * @property framesSent frames sent, retransmissions and heartbeats included.
 * @property fullStates `state_full` packets applied.
 * @property reducedStates `state_reduced` packets applied.
 * @property badCrc frames dropped because the CRC did not match (corrupted on the way).
 * @property badLength frames dropped because their length disagreed with the frame or the packet type (truncated).
 * @property tooShort frames shorter than a header and a CRC.
 * @property tooLong frames longer than the protocol allows (also those the transport's SLIP decoder cut off).
 * @property badFraming frames whose SLIP framing was broken (an invalid escape), dropped by the transport.
 * @property unknownType frames of a packet type this SDK does not know.
 * @property unexpected valid packets that make no sense here (host-to-robot types, settings data nobody asked for).
 * @property strayAcks acks and errors for no command in flight (late answers to a retransmitted command).
 * @property retransmissions commands sent again with the same sequence number after a timeout or reconnect.
 * @property refused commands the robot refused with an `error` packet.
 * @property robotErrors `error` packets about frames the robot dropped (it saw our bytes damaged).
 * @property reconnects links re-established after a loss.
 */
public class LinkStats internal constructor(
    public val framesReceived: Long,
    public val framesSent: Long,
    public val fullStates: Long,
    public val reducedStates: Long,
    public val badCrc: Long,
    public val badLength: Long,
    public val tooShort: Long,
    public val tooLong: Long,
    public val badFraming: Long,
    public val unknownType: Long,
    public val unexpected: Long,
    public val strayAcks: Long,
    public val retransmissions: Long,
    public val refused: Long,
    public val robotErrors: Long,
    public val reconnects: Long,
) {
    /** Frames dropped as corrupt, truncated, oversized, badly framed or unknown. */
    public val dropped: Long get() = badCrc + badLength + tooShort + tooLong + badFraming + unknownType

    private fun values() = longArrayOf(
        framesReceived, framesSent, fullStates, reducedStates, badCrc, badLength, tooShort, tooLong, badFraming,
        unknownType, unexpected, strayAcks, retransmissions, refused, robotErrors, reconnects,
    )

    // Field by field: a StateFlow compares every new snapshot with the last one, once per frame.
    override fun equals(other: Any?): Boolean = other is LinkStats && framesReceived == other.framesReceived &&
        framesSent == other.framesSent && fullStates == other.fullStates && reducedStates == other.reducedStates &&
        badCrc == other.badCrc && badLength == other.badLength && tooShort == other.tooShort && tooLong == other.tooLong &&
        badFraming == other.badFraming && unknownType == other.unknownType && unexpected == other.unexpected &&
        strayAcks == other.strayAcks && retransmissions == other.retransmissions && refused == other.refused &&
        robotErrors == other.robotErrors && reconnects == other.reconnects
    override fun hashCode(): Int = values().contentHashCode()
    override fun toString(): String =
        "LinkStats(received=$framesReceived, sent=$framesSent, full=$fullStates, reduced=$reducedStates, " +
            "dropped=$dropped [crc=$badCrc length=$badLength short=$tooShort long=$tooLong framing=$badFraming " +
            "unknown=$unknownType], unexpected=$unexpected, strayAcks=$strayAcks, retransmissions=$retransmissions, " +
            "refused=$refused, robotErrors=$robotErrors, reconnects=$reconnects)"

    internal companion object {
        val ZERO = LinkStats(0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)
    }
}

package org.pocketbot.sdk.transport

import org.pocketbot.protocol.Frames
import kotlin.math.ceil
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * How many bytes a second a link to a robot carries each way (docs/protocol.md, "Link rates"), and so how often it
 * can carry a packet: a state stream asked for faster than its link carries is cut by the robot's transmit buffer.
 *
 * ```
 * val period = robot.device.linkRate.periodFor(payloadBytes = 19, share = 0.6)   // 4 ms at 115200 Bd
 * ```
 */
public class LinkRate(public val bytesPerSecond: Int) {
    init {
        require(bytesPerSecond > 0) { "a link carries a positive number of bytes a second, not $bytesPerSecond" }
    }

    /** The time one frame with [payloadBytes] of payload takes on the link: SLIP ENDs, header and CRC included. */
    public fun frameTime(payloadBytes: Int): Duration = (wireBytes(payloadBytes) * 1000.0 / bytesPerSecond).milliseconds

    /**
     * The shortest period, in whole milliseconds (1 ms at least), at which frames of [payloadBytes] fill at most
     * [share] (0..1] of the link: the rest is left for commands, their answers and heartbeats.
     */
    public fun periodFor(payloadBytes: Int, share: Double): Duration {
        require(share > 0.0 && share <= 1.0) { "share must be in (0, 1], not $share" }
        val ms = wireBytes(payloadBytes) * 1000.0 / (bytesPerSecond * share)
        return maxOf(1L, ceil(ms - 1e-9).toLong()).milliseconds
    }

    override fun equals(other: Any?): Boolean = other is LinkRate && bytesPerSecond == other.bytesPerSecond
    override fun hashCode(): Int = bytesPerSecond
    override fun toString(): String = "LinkRate($bytesPerSecond B/s)"

    public companion object {
        /** A UART at [baud] with 8N1 framing: 10 bits per byte. */
        public fun ofBaud(baud: Int): LinkRate = LinkRate(baud / 10)

        /**
         * The PocketBot2's link: its UART at 115200 Bd, the Bluetooth SPP module bridging it, and the emulator's
         * simulated link by default.
         */
        public val SERIAL_115200: LinkRate = ofBaud(115_200)

        /** Bytes a frame with [payloadBytes] takes on a stream link: two SLIP ENDs, header, payload, CRC (escapes aside). */
        private fun wireBytes(payloadBytes: Int): Int = 2 + Frames.HEADER_SIZE + payloadBytes + Frames.CRC_SIZE
    }
}

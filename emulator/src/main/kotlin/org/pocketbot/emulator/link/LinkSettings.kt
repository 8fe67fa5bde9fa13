package org.pocketbot.emulator.link

import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * The simulated host link of one robot (a Bluetooth serial link, thesis ch. 7): how fast, how late, how
 * lossy. Applies to both directions; changeable while the emulator runs. Random effects come from the robot's
 * own seeded generator, so a run with the same seed and the same host traffic is the same.
 */
public class LinkSettings(
    /** Bits per second; every byte costs 10 bits (start, 8 data, stop). */
    public val baud: Int = 115_200,
    /** Delay from the last bit sent to the byte's arrival. */
    public val latency: Duration = 2.milliseconds,
    /** Extra delay, uniform in 0..jitter, per byte (order is kept, as on a serial link). */
    public val jitter: Duration = Duration.ZERO,
    /** Probability that a byte is lost. */
    public val lossRate: Double = 0.0,
    /** Probability that a byte arrives with one bit flipped. */
    public val corruptionRate: Double = 0.0,
    /** False: the link is down (out of range): host connections are dropped and no bytes pass. */
    public val connected: Boolean = true,
    /**
     * Host-to-robot bytes the link holds before they reach the robot (a Bluetooth SPP module's or a USB serial
     * adapter's buffer): a host that sends faster than the baud rate fills it, and what does not fit is lost
     * (counted in `RobotHandle.linkBytesOverflowed`) instead of piling up for minutes.
     */
    public val bufferBytes: Int = 2048,
) {
    init {
        require(baud in 300..10_000_000) { "baud $baud out of range" }
        require(!latency.isNegative() && !jitter.isNegative()) { "latency and jitter must not be negative" }
        require(lossRate in 0.0..1.0 && corruptionRate in 0.0..1.0) { "rates are probabilities" }
        require(bufferBytes >= 1) { "bufferBytes must be positive" }
    }

    /** These settings with the link up or down. */
    internal fun withConnected(connected: Boolean): LinkSettings =
        LinkSettings(baud, latency, jitter, lossRate, corruptionRate, connected, bufferBytes)

    override fun toString(): String =
        "LinkSettings(baud $baud, latency $latency, jitter $jitter, loss $lossRate, corruption $corruptionRate, " +
            "${if (connected) "connected" else "disconnected"}, buffer $bufferBytes B)"
}

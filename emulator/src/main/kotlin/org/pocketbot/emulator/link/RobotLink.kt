package org.pocketbot.emulator.link

import org.pocketbot.emulator.SimTime
import java.util.SplittableRandom
import java.util.concurrent.ConcurrentLinkedQueue

/** Receives the bytes a robot sends to its host, in order, on the emulator's stepping thread: must not block. */
public fun interface ByteSink {
    public fun onBytes(bytes: ByteArray)
}

/** A host-side connection to a robot's link: gets the robot's bytes, and is told when the link drops it. */
public interface LinkConnection : ByteSink {
    /** The link went down or another host took the robot over; the connection must close. */
    public fun onLinkLost(reason: String)
}

/**
 * The byte pipe between a robot's UART and its host, with the [LinkSettings] model. Host threads call
 * [hostSend], [attach], [detach]; the emulator's stepping thread does the rest.
 */
public class RobotLink internal constructor(private val rng: SplittableRandom) {
    @Volatile public var settings: LinkSettings = LinkSettings()
        internal set

    private val fromHost = ConcurrentLinkedQueue<ByteArray>()
    @Volatile private var connection: LinkConnection? = null

    // Host -> robot bytes scheduled in simulated time (ring buffer, times non-decreasing).
    private var rxTimes = LongArray(4096)
    private var rxBytes = ByteArray(4096)
    private var rxHead = 0
    private var rxCount = 0
    private var rxLineFree = 0L
    private var rxLastArrival = 0L

    // Robot -> host bytes in flight.
    private var txTimes = LongArray(1024)
    private var txBytes = ByteArray(1024)
    private var txHead = 0
    private var txCount = 0
    private var txLineFree = 0L
    private var txLastArrival = 0L
    private var txCredit = 0.0

    /** Bytes the robot sent and the link delivered to a host, and bytes dropped by the model (for tests). */
    @Volatile public var bytesToHost: Long = 0; private set
    @Volatile public var bytesLost: Long = 0; private set
    @Volatile public var bytesCorrupted: Long = 0; private set
    /** CRC-32 of every byte delivered to a host, in order: equal runs deliver equal bytes. */
    private val hostBytesCrc = java.util.zip.CRC32()
    public val bytesToHostCrc: Long get() = synchronized(hostBytesCrc) { hostBytesCrc.value }

    /** Connects a host; a robot link carries one host at a time, so an earlier one is told it lost the link. */
    public fun attach(c: LinkConnection) {
        if (!settings.connected) throw IllegalStateException("link is down")
        val old = synchronized(this) { connection.also { connection = c } }
        old?.onLinkLost("another host connected")
    }

    public fun detach(c: LinkConnection) {
        synchronized(this) { if (connection === c) connection = null }
    }

    public val isAttached: Boolean get() = connection != null

    /** Tells the connected host, if any, that the link is gone (the emulator closes). */
    internal fun dropConnection(reason: String) {
        val old = synchronized(this) { connection.also { connection = null } }
        old?.onLinkLost(reason)
    }

    /** Queues bytes from the host (already SLIP-framed); they enter the simulated link at the next step. */
    public fun hostSend(bytes: ByteArray) {
        if (bytes.isNotEmpty()) fromHost.add(bytes)
    }

    internal fun applySettings(s: LinkSettings) {
        val wasUp = settings.connected
        settings = s
        if (wasUp && !s.connected) {
            val old = synchronized(this) { connection.also { connection = null } }
            old?.onLinkLost("link disconnected")
            fromHost.clear()
        }
    }

    private fun byteTicks(): Long = SimTime.TICKS_PER_SECOND * 10 / settings.baud

    private fun delayTicks(s: LinkSettings): Long {
        var d = s.latency.inWholeNanoseconds * SimTime.TICKS_PER_SECOND / 1_000_000_000L
        if (s.jitter.isPositive()) d += (rng.nextDouble() * s.jitter.inWholeNanoseconds * SimTime.TICKS_PER_SECOND / 1e9).toLong()
        return d
    }

    /** Moves bytes the host queued into the simulated line, starting at [now]. */
    internal fun scheduleHostBytes(now: Long) {
        if (fromHost.isEmpty()) return
        val s = settings
        val bt = byteTicks()
        while (true) {
            val chunk = fromHost.poll() ?: break
            if (!s.connected) continue
            for (b in chunk) {
                rxLineFree = maxOf(rxLineFree, now) + bt
                if (s.lossRate > 0 && rng.nextDouble() < s.lossRate) { bytesLost++; continue }
                var v = b.toInt() and 0xff
                if (s.corruptionRate > 0 && rng.nextDouble() < s.corruptionRate) { v = v xor (1 shl rng.nextInt(8)); bytesCorrupted++ }
                val arrival = maxOf(rxLastArrival, rxLineFree + delayTicks(s))
                rxLastArrival = arrival
                pushRx(arrival, v.toByte())
            }
        }
    }

    private fun pushRx(time: Long, b: Byte) {
        if (rxCount == rxTimes.size) {
            val n = rxTimes.size * 2
            val t = LongArray(n); val y = ByteArray(n)
            for (i in 0 until rxCount) { t[i] = rxTimes[(rxHead + i) % rxTimes.size]; y[i] = rxBytes[(rxHead + i) % rxTimes.size] }
            rxTimes = t; rxBytes = y; rxHead = 0
        }
        val i = (rxHead + rxCount) % rxTimes.size
        rxTimes[i] = time; rxBytes[i] = b; rxCount++
    }

    /** Time of the next host byte due at the robot, or Long.MAX_VALUE. */
    internal fun nextRxTime(): Long = if (rxCount == 0) Long.MAX_VALUE else rxTimes[rxHead]

    internal fun popRx(): Int {
        val b = rxBytes[rxHead].toInt() and 0xff
        rxHead = (rxHead + 1) % rxTimes.size; rxCount--
        return b
    }

    /** How many bytes the UART may take from the firmware in a step of [stepTicks] at the link's baud rate. */
    internal fun txAllowance(stepTicks: Long): Int {
        txCredit = minOf(txCredit + settings.baud / 10.0 * stepTicks / SimTime.TICKS_PER_SECOND, MAX_TAKE.toDouble())
        return txCredit.toInt()
    }

    /** The firmware handed [n] bytes (at [address] in [mem]) to the UART at [now]. */
    internal fun robotSent(buffer: ByteArray, n: Int, now: Long) {
        txCredit -= n
        val s = settings
        if (!s.connected || connection == null) return
        val bt = byteTicks()
        for (k in 0 until n) {
            txLineFree = maxOf(txLineFree, now) + bt
            if (s.lossRate > 0 && rng.nextDouble() < s.lossRate) { bytesLost++; continue }
            var v = buffer[k].toInt() and 0xff
            if (s.corruptionRate > 0 && rng.nextDouble() < s.corruptionRate) { v = v xor (1 shl rng.nextInt(8)); bytesCorrupted++ }
            val arrival = maxOf(txLastArrival, txLineFree + delayTicks(s))
            txLastArrival = arrival
            if (txCount == txTimes.size) {
                val m = txTimes.size * 2
                val t = LongArray(m); val y = ByteArray(m)
                for (i in 0 until txCount) { t[i] = txTimes[(txHead + i) % txTimes.size]; y[i] = txBytes[(txHead + i) % txTimes.size] }
                txTimes = t; txBytes = y; txHead = 0
            }
            val i = (txHead + txCount) % txTimes.size
            txTimes[i] = arrival; txBytes[i] = v.toByte(); txCount++
        }
    }

    /** Hands the host every byte that has arrived by [now]. */
    internal fun deliverToHost(now: Long) {
        if (txCount == 0 || txTimes[txHead] > now) return
        var n = 0
        while (n < txCount && txTimes[(txHead + n) % txTimes.size] <= now) n++
        val out = ByteArray(n)
        for (k in 0 until n) { out[k] = txBytes[txHead]; txHead = (txHead + 1) % txTimes.size }
        txCount -= n
        bytesToHost += n
        synchronized(hostBytesCrc) { hostBytesCrc.update(out) }
        connection?.onBytes(out)
    }

    internal companion object {
        const val MAX_TAKE = 256
    }
}

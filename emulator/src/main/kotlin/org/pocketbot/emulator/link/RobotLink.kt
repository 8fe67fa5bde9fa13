package org.pocketbot.emulator.link

import org.pocketbot.emulator.SimTime
import java.util.SplittableRandom
import java.util.concurrent.ConcurrentLinkedQueue

/** Receives the bytes a robot sends to its host, in order, on the emulator's stepping thread: must not block. */
internal fun interface ByteSink {
    public fun onBytes(bytes: ByteArray)
}

/** A host-side connection to a robot's link: gets the robot's bytes, and is told when the link drops it. */
internal interface LinkConnection : ByteSink {
    /** The link went down (out of range, the emulator closed); the connection must close. */
    public fun onLinkLost(reason: String)
}

/**
 * The byte pipe between one of a robot's host links (link [index]; 0 is its UART) and the host on it, with the
 * [LinkSettings] model. Host threads call [hostSend], [attach] (through [RobotLinks]), [detach]; the emulator's
 * stepping thread does the rest, and tells the firmware when a host came ([takeOpen]) and when one left, once every
 * byte it sent has reached the robot ([takeClose]).
 */
internal class RobotLink(val index: Int, private val rng: SplittableRandom) {
    @Volatile public var settings: LinkSettings = LinkSettings()
        internal set

    private val fromHost = ConcurrentLinkedQueue<ByteArray>()
    /** Bytes in [fromHost], and those of [toRobot] that have not reached the robot yet: the link's buffer. */
    private val queuedFromHost = java.util.concurrent.atomic.AtomicInteger()
    @Volatile private var inFlightToRobot = 0
    @Volatile private var connection: LinkConnection? = null

    /** Host -> robot bytes scheduled in simulated time. Both directions start small and grow when a burst needs it:
     *  a fleet of a thousand robots keeps its links' state in a few cache lines instead of 40 KiB each. */
    private val toRobot = TimedBytes(INITIAL_CAPACITY)

    /** Robot -> host bytes in flight. */
    private val toHost = TimedBytes(INITIAL_CAPACITY)
    private var txCredit = 0.0

    /** Bytes the robot sent and the link delivered to a host, and bytes dropped by the model (for tests). */
    @Volatile public var bytesToHost: Long = 0; private set
    @Volatile public var bytesLost: Long = 0; private set
    @Volatile public var bytesCorrupted: Long = 0; private set
    /** Host bytes dropped because the link's buffer ([LinkSettings.bufferBytes]) was full. */
    private val overflowed = java.util.concurrent.atomic.AtomicLong()
    public val bytesOverflowed: Long get() = overflowed.get()
    /** CRC-32 of every byte delivered to a host, in order: equal runs deliver equal bytes. */
    private val hostBytesCrc = java.util.zip.CRC32()
    public val bytesToHostCrc: Long get() = synchronized(hostBytesCrc) { hostBytesCrc.value }

    // What the firmware is to be told at the next step: a host came (open), a host left (close, once its bytes are in).
    @Volatile private var opening = false
    @Volatile private var closing = false

    /** Connects [c] if no host is on this link, nor one that left with bytes still on their way; false otherwise. */
    internal fun tryAttach(c: LinkConnection): Boolean = synchronized(this) {
        if (connection != null || !drained) return false
        connection = c
        closing = false
        opening = true
        true
    }

    public fun detach(c: LinkConnection) {
        synchronized(this) {
            if (connection !== c) return
            connection = null
            closing = true
        }
    }

    public val isAttached: Boolean get() = connection != null

    /** Nothing from the host is left on the way to the robot. */
    private val drained: Boolean get() = queuedFromHost.get() == 0 && inFlightToRobot == 0

    /** True once: a host came since the firmware was last told. */
    internal fun takeOpen(): Boolean = opening.also { if (it) opening = false }

    /** True once: the host left and everything it sent has reached the robot. */
    internal fun takeClose(): Boolean = synchronized(this) { (closing && connection == null && drained).also { if (it) closing = false } }

    /** The firmware has yet to be told that a host came or left. */
    internal val pending: Boolean get() = opening || closing

    /** Bytes from no connection (a test's, a bench's): the firmware is told a host came if none is on the link. */
    internal fun rawSend(bytes: ByteArray) {
        if (connection == null) opening = true
        hostSend(bytes)
    }

    /** Tells the connected host, if any, that the link is gone (the emulator closes). */
    internal fun dropConnection(reason: String) {
        val old = synchronized(this) { connection.also { if (it != null) { connection = null; closing = true } } }
        old?.onLinkLost(reason)
    }

    /**
     * Queues bytes from the host (already SLIP-framed); they enter the simulated link at the next step. What does
     * not fit in the link's buffer (bytes queued and on the wire but not yet at the robot) is dropped and counted,
     * as a serial link without flow control would.
     */
    public fun hostSend(bytes: ByteArray) {
        if (bytes.isEmpty()) return
        val capacity = settings.bufferBytes
        while (true) {
            val queued = queuedFromHost.get()
            val room = capacity - queued - inFlightToRobot
            val take = minOf(bytes.size, maxOf(room, 0))
            if (take == 0) { overflowed.addAndGet(bytes.size.toLong()); return }
            if (!queuedFromHost.compareAndSet(queued, queued + take)) continue
            if (take < bytes.size) overflowed.addAndGet((bytes.size - take).toLong())
            fromHost.add(if (take == bytes.size) bytes else bytes.copyOf(take))
            return
        }
    }

    internal fun applySettings(s: LinkSettings) {
        val wasUp = settings.connected
        settings = s
        if (wasUp && !s.connected) {
            while (true) { val chunk = fromHost.poll() ?: break; queuedFromHost.addAndGet(-chunk.size) }
            dropConnection("link disconnected")
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
            queuedFromHost.addAndGet(-chunk.size)
            if (!s.connected) continue
            for (b in chunk) transmit(toRobot, b.toInt() and 0xff, now, s, bt)
        }
        inFlightToRobot = toRobot.size
    }

    /** Time of the next host byte due at the robot, or Long.MAX_VALUE. */
    internal fun nextRxTime(): Long = toRobot.nextTime()

    internal fun popRx(): Int = toRobot.pop().also { inFlightToRobot = toRobot.size }

    /** How many bytes the UART may take from the firmware in a step of [stepTicks] at the link's baud rate. */
    internal fun txAllowance(stepTicks: Long): Int {
        txCredit = minOf(txCredit + settings.baud / 10.0 * stepTicks / SimTime.TICKS_PER_SECOND, MAX_TAKE.toDouble())
        return txCredit.toInt()
    }

    /** The firmware handed the first [n] bytes of [buffer] to the UART at [now]. */
    internal fun robotSent(buffer: ByteArray, n: Int, now: Long) {
        txCredit -= n
        val s = settings
        if (!s.connected || connection == null) return
        val bt = byteTicks()
        for (k in 0 until n) transmit(toHost, buffer[k].toInt() and 0xff, now, s, bt)
    }

    /** Puts one byte on [line] at [now]: the baud rate, then the fault model (loss, corruption, latency). */
    private fun transmit(line: TimedBytes, byte: Int, now: Long, s: LinkSettings, byteTicks: Long) {
        line.lineFree = maxOf(line.lineFree, now) + byteTicks
        if (s.lossRate > 0 && rng.nextDouble() < s.lossRate) { bytesLost++; return }
        var v = byte
        if (s.corruptionRate > 0 && rng.nextDouble() < s.corruptionRate) { v = v xor (1 shl rng.nextInt(8)); bytesCorrupted++ }
        // Bytes never overtake each other, whatever the jitter.
        val arrival = maxOf(line.lastArrival, line.lineFree + delayTicks(s))
        line.lastArrival = arrival
        line.push(arrival, v.toByte())
    }

    /** Hands the host every byte that has arrived by [now]. */
    internal fun deliverToHost(now: Long) {
        val out = toHost.popUntil(now) ?: return
        val n = out.size
        bytesToHost += n
        synchronized(hostBytesCrc) { hostBytesCrc.update(out) }
        connection?.onBytes(out)
    }

    internal companion object {
        const val MAX_TAKE = 256
        private const val INITIAL_CAPACITY = 64
    }
}

/** One direction of a link: bytes with their arrival times (non-decreasing), in a growable ring. */
private class TimedBytes(capacity: Int) {
    private var times = LongArray(capacity)
    private var bytes = ByteArray(capacity)
    private var head = 0
    private var count = 0

    val size: Int get() = count

    /** When the line has finished sending what it was handed so far, and when its last byte arrives. */
    var lineFree = 0L
    var lastArrival = 0L

    fun push(time: Long, b: Byte) {
        if (count == times.size) {
            val n = times.size * 2
            val t = LongArray(n); val y = ByteArray(n)
            for (i in 0 until count) { t[i] = times[(head + i) % times.size]; y[i] = bytes[(head + i) % times.size] }
            times = t; bytes = y; head = 0
        }
        val i = (head + count) % times.size
        times[i] = time; bytes[i] = b; count++
    }

    /** Arrival time of the oldest byte, or Long.MAX_VALUE when empty. */
    fun nextTime(): Long = if (count == 0) Long.MAX_VALUE else times[head]

    fun pop(): Int {
        val b = bytes[head].toInt() and 0xff
        head = (head + 1) % times.size; count--
        return b
    }

    /** Every byte that has arrived by [now], oldest first, or null when none has. */
    fun popUntil(now: Long): ByteArray? {
        if (nextTime() > now) return null
        var n = 0
        while (n < count && times[(head + n) % times.size] <= now) n++
        return ByteArray(n) { pop().toByte() }
    }
}

package org.pocketbot.emulator

import kotlinx.coroutines.runBlocking
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.ProtocolError
import org.pocketbot.sdk.transport.Transport

/** A minimal host for tests: speaks the protocol through sdk-core's codecs over an in-process transport. */
class TestHost(val robot: RobotHandle) : AutoCloseable {
    val transport: Transport = robot.openTransport()
    private var seq = 0
    val packets = ArrayList<Packet>()
    val errors = ArrayList<ProtocolError>()

    /** Sends [packet]; commands that want an ack get the next sequence number. */
    fun send(packet: Packet, acked: Boolean = true): Int {
        val s = if (acked) { seq = seq % 255 + 1; seq } else 0
        runBlocking { transport.send(Frames.encode(packet, s)) }
        return s
    }

    /** Decodes every frame that arrived so far. */
    fun drain(): List<Packet> {
        val fresh = ArrayList<Packet>()
        while (true) {
            val frame = transport.incoming.tryReceive().getOrNull() ?: break
            when (val r = Frames.decode(frame)) {
                is FrameResult.Decoded -> fresh += r.packet
                is FrameResult.Failed -> errors += r.error
            }
        }
        packets += fresh
        return fresh
    }

    /**
     * Runs the emulator for [duration] while keeping the link alive like a real host does (a heartbeat every
     * 250 ms; the firmware's link failsafe stops host-driven motion after 1 s of silence).
     */
    fun run(duration: kotlin.time.Duration) { runUntil(duration) { false } }

    /** Like [run], until [condition] holds (checked every 10 ms); true if it held. */
    fun runUntil(timeout: kotlin.time.Duration, condition: () -> Boolean): Boolean {
        val emu = robot.emulator
        val end = emu.timeTicks + SimTime.fromDuration(timeout)
        var sinceBeat = 0
        while (emu.timeTicks < end) {
            if (condition()) return true
            emu.runFor(kotlin.time.Duration.parse("10ms"))
            sinceBeat += 10
            if (sinceBeat >= 250) { send(org.pocketbot.protocol.Heartbeat, acked = false); sinceBeat = 0 }
        }
        return condition()
    }

    override fun close() = transport.close()
}

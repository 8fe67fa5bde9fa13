package org.pocketbot.emulator

import kotlinx.coroutines.runBlocking
import org.pocketbot.protocol.Ack
import org.pocketbot.protocol.Driver
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Heartbeat
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.HostRole
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.ProtocolError
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.SetRole
import org.pocketbot.sdk.transport.Transport
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * A minimal host for tests: speaks the protocol through the generated codecs over an in-process transport, with
 * its own session and sequence numbers, and keeps every packet it received (with its frame's seq). Unless told not
 * to ([handshake] false), it begins as a host does: hello_request, then set_role to drive the robot.
 */
class TestHost(val robot: RobotHandle, val session: Long = 0x5E55_1001L, firstSeq: Int = 1, handshake: Boolean = true) : AutoCloseable {
    val transport: Transport = robot.openTransport()
    private var seq = firstSeq - 1
    /** Every packet received so far, in order, with the seq of its frame. */
    val received = ArrayList<Pair<Int, Packet>>()
    val packets: List<Packet> get() = received.map { it.second }
    val errors = ArrayList<ProtocolError>()

    /** Sends [packet]; acked commands get the next sequence number (1..255) unless [seq] is given. */
    fun send(packet: Packet, acked: Boolean = true, seq: Int? = null): Int {
        val s = seq ?: if (acked) { this.seq = this.seq % 255 + 1; this.seq } else 0
        runBlocking { transport.send(Frames.encode(packet, s)) }
        return s
    }

    /** Sends a complete frame as it is (already encoded, without SLIP). */
    fun sendFrame(frame: ByteArray) { runBlocking { transport.send(frame) } }

    /** Decodes every frame that arrived so far. */
    fun drain(): List<Packet> {
        val fresh = ArrayList<Packet>()
        while (true) {
            val frame = transport.incoming.tryReceive().getOrNull() ?: break
            when (val r = Frames.decode(frame)) {
                is FrameResult.Decoded -> { fresh += r.packet; received += r.seq to r.packet }
                is FrameResult.Failed -> errors += r.error
            }
        }
        return fresh
    }

    inline fun <reified T : Packet> all(): List<T> { drain(); return packets.filterIsInstance<T>() }

    /** The ack of the command sent with [seq], if it arrived. */
    fun ackOf(seq: Int): Ack? { drain(); return received.firstOrNull { it.first == seq && it.second is Ack }?.second as Ack? }

    /**
     * hello_request with this host's session, then set_role ([role], by default to drive); waits for the hello and
     * the role's ack (simulated time) and returns the hello.
     */
    fun hello(timeout: Duration = 500.milliseconds, role: HostRole = HostRole.DRIVE): Hello {
        val before = all<Hello>().size
        send(HelloRequest(ProtocolInfo.VERSION, session), acked = false, seq = HELLO_SEQ)
        check(runUntil(timeout) { all<Hello>().size > before }) { "no hello within $timeout" }
        val asked = send(SetRole(role.code, "test@emulator"))
        check(runUntil(timeout) { ackOf(asked) != null }) { "set_role not acknowledged within $timeout" }
        return all<Hello>()[before]
    }

    init {
        if (handshake) hello()
    }

    /** Who drives, as the robot last told this host. */
    fun driver(): Driver? = all<Driver>().lastOrNull()

    /**
     * Runs the emulator for [duration] while keeping the link alive like a real host does (a heartbeat every
     * 250 ms; the firmware's link failsafe stops host-driven motion after 1 s of silence).
     */
    fun run(duration: Duration) { runUntil(duration) { false } }

    /** Like [run], until [condition] holds (checked every 10 ms); true if it held. */
    fun runUntil(timeout: Duration, condition: () -> Boolean): Boolean {
        val emu = robot.emulator
        val end = emu.timeTicks + SimTime.fromDuration(timeout)
        var sinceBeat = 0
        while (emu.timeTicks < end) {
            if (condition()) return true
            emu.runFor(10.milliseconds)
            sinceBeat += 10
            if (sinceBeat >= 250) { send(Heartbeat, acked = false); sinceBeat = 0 }
        }
        return condition()
    }

    override fun close() = transport.close()

    companion object {
        /** The sequence number of this host's hello_request: the robot's answer carries it. */
        const val HELLO_SEQ: Int = 77
    }
}

package org.pocketbot.sdk.internal.link

import kotlinx.coroutines.CompletableDeferred
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Packet
import org.pocketbot.sdk.CommandWindowFullException

/** One acknowledged command on its way: the frame is encoded once, so a retransmission is byte for byte the same. */
internal class PendingCommand(val seq: Int, val packet: Packet) {
    val frame: ByteArray = Frames.encode(packet, seq)

    /** Completes with the ack, or exceptionally with the robot's refusal. */
    val answer = CompletableDeferred<Unit>()

    /** The session it was last sent in; null when it must (still or again) be sent. */
    var sentIn: Session? = null

    /** True once it went out at least once: the robot may hold it even if no ack came back. */
    var everSent = false

    /** Asked before every transmission: false withdraws the command (a stop was issued after it). */
    var wanted: () -> Boolean = { true }
}

/**
 * The sequence numbers of the acknowledged commands awaiting an answer. Numbers run 1..255 and skip the ones in
 * use; at most [window] commands wait at a time, so a robot that never answers cannot make the host spin or pile
 * up commands: the newest is refused with [CommandWindowFullException]. Touched only on the link's serial context.
 */
internal class CommandTable(private val window: Int = DEFAULT_WINDOW) {
    private val pending = HashMap<Int, PendingCommand>()
    private var lastSeq = 0

    init {
        require(window in 1..MAX_SEQ) { "window $window outside 1..$MAX_SEQ" }
    }

    val size: Int get() = pending.size

    /** A new pending command with the next free sequence number. */
    fun open(packet: Packet): PendingCommand {
        if (pending.size >= window) throw CommandWindowFullException(window)
        do {
            lastSeq = lastSeq % MAX_SEQ + 1
        } while (lastSeq in pending)
        return PendingCommand(lastSeq, packet).also { pending[it.seq] = it }
    }

    fun close(p: PendingCommand) {
        if (pending[p.seq] === p) pending.remove(p.seq)
    }

    /** The pending command [seq] if it is of [type]; a late answer to a finished command finds nothing. */
    fun find(seq: Int, type: Int): PendingCommand? = pending[seq]?.takeIf { it.packet.type == type }

    companion object {
        const val MAX_SEQ: Int = 255
        const val DEFAULT_WINDOW: Int = 32
    }
}

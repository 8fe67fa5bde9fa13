package org.pocketbot.sdk

import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.channels.ReceiveChannel
import org.pocketbot.protocol.Ack
import org.pocketbot.protocol.Error
import org.pocketbot.protocol.ErrorCode
import org.pocketbot.protocol.FieldType
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.LoadDefaults
import org.pocketbot.protocol.MoveArc
import org.pocketbot.protocol.MoveRotate
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.MovementDone
import org.pocketbot.protocol.PACKET_SPECS
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.RobotState
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.SaveSettings
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.SettingsData
import org.pocketbot.protocol.StateFull
import org.pocketbot.protocol.StateReduced
import org.pocketbot.protocol.Stop
import org.pocketbot.protocol.UpdateSettings
import org.pocketbot.sdk.internal.DEFAULT_SETTINGS_BYTES
import org.pocketbot.sdk.internal.EMPTY_STATE
import org.pocketbot.sdk.internal.readNumber
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport
import org.pocketbot.sdk.transport.TransportLostException

/**
 * An in-memory robot that speaks the protocol like the firmware: hello, acks with a retransmission history,
 * read/update settings with the firmware's bounds checks, a movement queue. Tests script what it sends (states,
 * movement completions) and inject faults (lost frames in either direction, corruption, disconnects).
 * Everything runs synchronously inside [Transport.send], so tests are deterministic.
 */
class ScriptedRobot(
    var robotId: Int = 7,
    var name: String = "Scripted",
    var protocolVersion: Int = ProtocolInfo.VERSION,
    var layoutHash: Long = ProtocolInfo.LAYOUT_HASH,
) {
    val settings: ByteArray = DEFAULT_SETTINGS_BYTES.copyOf().also { it[0] = robotId.toByte() }
    var state: RobotState = EMPTY_STATE

    /** Every valid frame the host sent, in order: (seq, packet). */
    val received = mutableListOf<Pair<Int, Packet>>()

    /** Commands executed (not re-acked retransmissions). */
    val executed = mutableListOf<Packet>()

    val queue = ArrayDeque<Int>()
    var finishedId = 0
    var syncMode = 1
    var syncPeriodMs = 100

    /** Host frames to swallow before they reach the robot (loss host -> robot). */
    var dropIncoming = 0

    /** Robot frames to swallow on the way out (loss robot -> host), e.g. an ack. */
    var dropOutgoing = 0

    /** When set, decides per outgoing packet whether to drop it. */
    var dropOutgoingIf: ((Packet) -> Boolean)? = null

    /** Refuse this many [RobotDevice.open] calls. */
    var refuseOpens = 0

    /** Answer hello requests at all. */
    var answersHello = true
    var opens = 0
    private val history = ArrayDeque<Pair<Int, Int>>()
    private var link: Link? = null

    inner class Link : Transport {
        val channel = Channel<ByteArray>(Channel.UNLIMITED)
        override val address: String = "scripted:$robotId"
        override val incoming: ReceiveChannel<ByteArray> get() = channel
        var open = true

        override suspend fun send(frame: ByteArray) {
            if (!open) throw TransportLostException("closed")
            onFrame(frame)
        }

        override fun close() {
            open = false
            channel.close()
        }
    }

    val device: RobotDevice = object : RobotDevice {
        override val name: String get() = this@ScriptedRobot.name
        override val address: String get() = "scripted:$robotId"
        override suspend fun open(): Transport {
            opens++
            if (refuseOpens > 0) {
                refuseOpens--
                throw TransportLostException("robot out of range")
            }
            return Link().also { link = it }
        }
    }

    val connected: Boolean get() = link?.open == true

    /** The link breaks: the host sees its incoming channel fail. */
    fun disconnect() {
        val l = link ?: return
        l.open = false
        l.channel.close(TransportLostException("link dropped"))
        link = null
    }

    /** Sends raw bytes as one frame (to inject garbage). */
    fun sendRaw(frame: ByteArray) {
        link?.channel?.trySend(frame)
    }

    fun send(packet: Packet, seq: Int = 0) {
        val l = link ?: return
        if (dropOutgoing > 0) {
            dropOutgoing--
            return
        }
        if (dropOutgoingIf?.invoke(packet) == true) return
        l.channel.trySend(Frames.encode(packet, seq))
    }

    fun sendState(s: RobotState = state) {
        state = s
        send(StateFull(s))
    }

    fun sendReduced(r: StateReduced) = send(StateReduced(r.timeMs, r.encoderLeft, r.encoderRight, r.speedLeftMmps, r.speedRightMmps, r.linePosition, r.lineFlags))

    /** The running movement finishes: movement_done and the state say so. */
    fun finishMovement(announce: Boolean = true) {
        val id = queue.removeFirst()
        finishedId = id
        state = state.copy(locomotion = state.locomotion.copy(finishedId = id, currentId = queue.firstOrNull() ?: 0, queueLength = queue.size))
        if (announce) send(MovementDone(id))
    }

    private fun hello() = Hello(robotId, name, 0, 1, 0, protocolVersion, layoutHash, ProtocolInfo.SETTINGS_SIZE, ProtocolInfo.STATE_SIZE)

    private fun onFrame(frame: ByteArray) {
        if (dropIncoming > 0) {
            dropIncoming--
            return
        }
        val decoded = Frames.decode(frame) as? FrameResult.Decoded ?: return
        val (seq, packet) = decoded
        received += seq to packet
        val spec = PACKET_SPECS.getValue(packet.type)
        if (packet is HelloRequest) {
            if (answersHello) send(hello())
            return
        }
        if (!spec.acked) return
        if (packet !is ReadSettings && history.contains(seq to packet.type)) {
            send(Ack(packet.type), seq)
            return
        }
        val refusal = execute(packet)
        if (refusal != null) {
            send(Error(refusal.first.code, packet.type, seq, refusal.second), seq)
            return
        }
        executed += packet
        history.addLast(seq to packet.type)
        if (history.size > 8) history.removeFirst()
        if (packet is ReadSettings) {
            var offset = 0
            while (offset < settings.size) {
                val n = minOf(64, settings.size - offset)
                send(SettingsData(offset, settings.copyOfRange(offset, offset + n)))
                offset += n
            }
        }
        send(Ack(packet.type), seq)
    }

    /** null to accept, or the error code and detail. */
    private fun execute(packet: Packet): Pair<ErrorCode, Int>? {
        when (packet) {
            is UpdateSettings -> {
                val start = SETTINGS_FIELDS.firstOrNull { it.offset == packet.offset } ?: return ErrorCode.SETTINGS_RANGE to packet.offset
                val end = packet.offset + packet.data.size
                if (SETTINGS_FIELDS.none { it.offset + it.size == end }) return ErrorCode.SETTINGS_RANGE to packet.data.size
                val candidate = settings.copyOf()
                packet.data.copyInto(candidate, packet.offset)
                for (f in SETTINGS_FIELDS.filter { it.offset >= start.offset && it.offset < end }) {
                    if (f.type == FieldType.CHAR) continue
                    for (i in 0 until f.count) {
                        val v = readNumber(candidate, f.offset + i * f.type.size, f.type).toDouble()
                        val lo = f.min
                        val hi = f.max
                        if ((lo != null && v < lo) || (hi != null && v > hi) || v.isNaN()) return ErrorCode.SETTINGS_VALUE to f.offset
                    }
                }
                candidate.copyInto(settings)
            }
            is SetSync -> {
                if (packet.mode > 2 || packet.periodMs == 0) return ErrorCode.BAD_ARGUMENT to packet.mode
                syncMode = packet.mode
                syncPeriodMs = packet.periodMs
            }
            is MoveStraight -> return enqueue(packet.id)
            is MoveRotate -> return enqueue(packet.id)
            is MoveArc -> return enqueue(packet.id)
            is Stop -> queue.clear()
            is LoadDefaults -> DEFAULT_SETTINGS_BYTES.copyInto(settings)
            is SaveSettings, is ReadSettings -> {}
            else -> {}
        }
        return null
    }

    private fun enqueue(id: Int): Pair<ErrorCode, Int>? {
        if (queue.size >= 8) return ErrorCode.QUEUE_FULL to queue.size
        queue.addLast(id)
        state = state.copy(locomotion = state.locomotion.copy(mode = 1, currentId = queue.first(), queueLength = queue.size))
        return null
    }
}

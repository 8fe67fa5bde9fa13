package org.pocketbot.sdk

import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.channels.ReceiveChannel
import org.pocketbot.protocol.Ack
import org.pocketbot.protocol.Crc16
import org.pocketbot.protocol.Driver
import org.pocketbot.protocol.DriverChange
import org.pocketbot.protocol.Error
import org.pocketbot.protocol.ErrorCode
import org.pocketbot.protocol.FieldType
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Goodbye
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.HostRole
import org.pocketbot.protocol.LoadDefaults
import org.pocketbot.protocol.MoveArc
import org.pocketbot.protocol.MoveRotate
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.MovementDone
import org.pocketbot.protocol.MovementLog
import org.pocketbot.protocol.MovementOutcome
import org.pocketbot.protocol.PACKET_SPECS
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.ReadMovements
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.RobotState
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.SaveSettings
import org.pocketbot.protocol.SetRole
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.SettingsData
import org.pocketbot.protocol.StateFull
import org.pocketbot.protocol.StateLocomotion
import org.pocketbot.protocol.StateReduced
import org.pocketbot.protocol.Stop
import org.pocketbot.protocol.UpdateSettings
import org.pocketbot.sdk.internal.DEFAULT_SETTINGS_BYTES
import org.pocketbot.sdk.internal.readNumber
import org.pocketbot.sdk.transport.LinkRate
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport
import org.pocketbot.sdk.transport.TransportLostException

/**
 * An in-memory robot that speaks the protocol like the firmware: hello with host sessions, the driver rule (the host
 * drives unless [otherDriver] does; a watcher's commands are refused), acks with a retransmission history (same
 * session, same bytes), read/update settings with the firmware's bounds checks, a movement queue with results and a
 * log. Tests script what it sends (states, movement ends) and inject faults (lost
 * frames in either direction, disconnects, resets). Everything runs synchronously inside [Transport.send], so tests
 * are deterministic.
 */
class ScriptedRobot(
    var robotId: Int = 7,
    val address: String = "scripted:$robotId",
    var name: String = "Scripted",
    var protocolVersion: Int = ProtocolInfo.VERSION,
    var layoutHash: Long = ProtocolInfo.LAYOUT_HASH,
) {
    val settings: ByteArray = DEFAULT_SETTINGS_BYTES.copyOf().also { it[offsetOf("identity.robot_id")] = robotId.toByte() }

    /** Writes [value] into the robot's own settings behind the host's back (another host, the EEPROM at a reset). */
    fun poke(name: String, value: Number) {
        val f = SETTINGS_FIELDS.single { it.path == name }
        org.pocketbot.sdk.internal.writeNumber(settings, f.offset, f.type, value, name)
    }
    var state: RobotState = WIRE_EMPTY

    /** Every valid frame the host sent, in order: (seq, packet). */
    val received = mutableListOf<Pair<Int, Packet>>()

    /** Commands executed (not re-acked retransmissions). */
    val executed = mutableListOf<Packet>()

    val queue = ArrayDeque<Int>()
    var finishedId = 0

    /** Movement results, oldest first, as the firmware's log keeps them (the last 16). */
    val log = ArrayDeque<Triple<Int, MovementOutcome, Float>>()

    /** The host session the robot serves; 0 after a reset. */
    var session = 0L

    /** The label of another host that drives the robot, or null; set it to play that host. */
    var otherDriver: String? = null

    /** True while the host under test drives. */
    var hostDrives = false
        private set
    private var hostLabel = ""
    var syncMode = 1
    var syncPeriodMs = 100

    /** Host frames to swallow before they reach the robot (loss host -> robot). */
    var dropIncoming = 0

    /** Robot frames to swallow on the way out (loss robot -> host), e.g. an ack. */
    var dropOutgoing = 0

    /** When set, decides per outgoing packet whether to drop it. */
    var dropOutgoingIf: ((Packet) -> Boolean)? = null

    /** When set, decides per outgoing packet whether it arrives garbled (a bad CRC), as a noisy link delivers it. */
    var garbleOutgoingIf: ((Packet) -> Boolean)? = null

    /** Refuse this many [RobotDevice.open] calls. */
    var refuseOpens = 0

    /** Commands the robot swallows without an answer (a broken firmware). */
    var refuseToAck: ((Packet) -> Boolean)? = null

    /** Says hello without being asked (sequence 0), as at a reset, but keeps everything (a glitching robot). */
    fun sayHelloUnasked() = send(hello(resumed = false))

    /** Answer hello requests at all. */
    var answersHello = true

    /** How fast the link to this robot is, as its device says. */
    var linkRate: LinkRate = LinkRate.SERIAL_115200
    var opens = 0
    private val history = ArrayDeque<Pair<Int, List<Byte>>>()
    private var link: Link? = null

    inner class Link : Transport {
        val channel = Channel<ByteArray>(Channel.UNLIMITED)
        override val address: String = this@ScriptedRobot.address
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
        override val address: String get() = this@ScriptedRobot.address
        override val linkRate: LinkRate get() = this@ScriptedRobot.linkRate
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
        val frame = Frames.encode(packet, seq)
        if (garbleOutgoingIf?.invoke(packet) == true) frame[frame.size - 1] = (frame[frame.size - 1].toInt() xor 0x5A).toByte()
        l.channel.trySend(frame)
    }

    fun sendState(s: RobotState = state) {
        state = s
        send(StateFull(s))
    }

    fun sendReduced(r: StateReduced) = send(StateReduced(r.timeMs, r.encoderLeft, r.encoderRight, r.speedLeftMmps, r.speedRightMmps, r.linePosition, r.lineFlags))

    /** The running movement ends ([outcome], [done] of it): the log, the state and (if [announce]) movement_done say so. */
    fun finishMovement(announce: Boolean = true, outcome: MovementOutcome = MovementOutcome.FINISHED, done: Float = 0.1f) {
        val id = queue.removeFirst()
        if (outcome == MovementOutcome.FINISHED) finishedId = id
        record(id, outcome, done, announce)
        updateLocomotion()
    }

    private fun record(id: Int, outcome: MovementOutcome, done: Float, announce: Boolean) {
        log.addLast(Triple(id, outcome, done))
        if (log.size > 16) log.removeFirst()
        if (announce) send(MovementDone(id, outcome.code, done))
    }

    /** The queue is cleared by [outcome]: the running movement gets [doneRunning], the rest nothing. */
    fun clearQueue(outcome: MovementOutcome, doneRunning: Float = 0.05f, announce: Boolean = true) {
        var first = true
        while (queue.isNotEmpty()) {
            val id = queue.removeFirst()
            val o = if (first) outcome else if (outcome == MovementOutcome.FAILSAFE) outcome else MovementOutcome.DROPPED
            record(id, o, if (first) doneRunning else 0f, announce)
            first = false
        }
        updateLocomotion()
    }

    /** Another host takes the robot over: the host under test is told, and watches. */
    fun takenOverBy(label: String) {
        otherDriver = label
        hostDrives = false
        sayWhoDrives(DriverChange.TAKEN_OVER)
    }

    private fun sayWhoDrives(change: DriverChange, seq: Int = 0) = send(
        Driver(if (hostDrives) HostRole.DRIVE.code else HostRole.WATCH.code, change.code,
            if (hostDrives) hostLabel else otherDriver ?: "", state.time.timeMs),
        seq,
    )

    /** Power cycle: queue, log, session, history and the drive are gone; the robot says hello unasked. */
    fun reset() {
        queue.clear()
        log.clear()
        history.clear()
        hostDrives = false
        otherDriver = null
        session = 0
        finishedId = 0
        state = WIRE_EMPTY
        send(hello(resumed = false))
    }

    private fun updateLocomotion() {
        state = RobotState(
            time = state.time, encoders = state.encoders, wheels = state.wheels, line = state.line,
            lineFollow = state.lineFollow, proximity = state.proximity, colour = state.colour, accel = state.accel,
            power = state.power, indicators = state.indicators,
            locomotion = StateLocomotion(
                mode = if (queue.isEmpty()) org.pocketbot.protocol.LocoMode.IDLE else org.pocketbot.protocol.LocoMode.MOVEMENT, queueLength = queue.size, currentId = queue.firstOrNull() ?: 0, finishedId = finishedId,
            ),
            track = state.track, errors = state.errors,
        )
    }

    private fun hello(resumed: Boolean) = Hello(
        robotId, name, 0, 1, 0, protocolVersion, layoutHash, ProtocolInfo.SETTINGS_SIZE, ProtocolInfo.STATE_SIZE,
        if (resumed) 1 else 0, Crc16.compute(settings),
    )

    private fun movementLog(): MovementLog {
        val entries = log.toList()
        return MovementLog(
            queue.firstOrNull() ?: 0, queue.size, entries.size,
            List(16) { entries.getOrNull(it)?.first ?: 0 },
            List(16) { entries.getOrNull(it)?.second?.code ?: 0 },
            List(16) { entries.getOrNull(it)?.third ?: 0f },
        )
    }

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
            val resumed = packet.session != 0L && packet.session == session
            if (!resumed) history.clear()
            session = packet.session
            if (answersHello) send(hello(resumed), seq)
            return
        }
        if (!spec.watcherOk && !hostDrives) {
            sayWhoDrives(DriverChange.NONE)
            send(Error(ErrorCode.NOT_DRIVER.code, packet.type, seq, 0), seq)
            return
        }
        if (!spec.acked) return
        if (refuseToAck?.invoke(packet) == true) return
        val content = frame.toList()
        if (!spec.idempotent && history.contains(seq to content)) {
            send(Ack(packet.type), seq)
            return
        }
        val refusal = execute(packet)
        if (refusal != null) {
            send(Error(refusal.first.code, packet.type, seq, refusal.second), seq)
            return
        }
        executed += packet
        history.addLast(seq to content)
        if (history.size > 8) history.removeFirst()
        if (packet is ReadMovements) send(movementLog())
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
                if (SETTINGS_FIELDS.none { it.offset + it.size == end }) return ErrorCode.SETTINGS_RANGE to packet.offset
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
                // The firmware keeps the sync mode in its settings too.
                poke("sync.mode", packet.mode)
                poke("sync.period_ms", packet.periodMs)
            }
            is SetRole -> {
                hostLabel = packet.label
                val before = hostDrives
                val tookFrom = otherDriver
                hostDrives = when (packet.role) {
                    HostRole.WATCH.code -> false
                    HostRole.TAKE_OVER.code -> true.also { otherDriver = null }
                    else -> hostDrives || otherDriver == null
                }
                sayWhoDrives(
                    when {
                        !hostDrives || before -> DriverChange.NONE
                        packet.role == HostRole.TAKE_OVER.code && tookFrom != null -> DriverChange.TAKEN_OVER
                        else -> DriverChange.CLAIMED
                    },
                )
            }
            is Goodbye -> hostDrives = false
            is MoveStraight -> return enqueue(packet.id)
            is MoveRotate -> return enqueue(packet.id)
            is MoveArc -> return enqueue(packet.id)
            is Stop -> clearQueue(MovementOutcome.STOPPED)
            is LoadDefaults -> DEFAULT_SETTINGS_BYTES.copyInto(settings)
            is SaveSettings, is ReadSettings -> {}
            else -> {}
        }
        return null
    }

    private fun enqueue(id: Int): Pair<ErrorCode, Int>? {
        if (queue.size >= 8) return ErrorCode.QUEUE_FULL to queue.size
        queue.addLast(id)
        updateLocomotion()
        return null
    }
}

package org.pocketbot.sdk

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.CoroutineName
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.ExperimentalCoroutinesApi
import kotlinx.coroutines.Job
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.channels.BufferOverflow
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.MutableSharedFlow
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.SharedFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asSharedFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.launch
import kotlinx.coroutines.selects.select
import kotlinx.coroutines.sync.Mutex
import kotlinx.coroutines.sync.withLock
import kotlinx.coroutines.withContext
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.protocol.Ack
import org.pocketbot.protocol.DebugText
import org.pocketbot.protocol.Error
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Heartbeat
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.IrReceived
import org.pocketbot.protocol.MovementDone
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.ProtocolError
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.RobotState
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.SettingsData
import org.pocketbot.protocol.StateFull
import org.pocketbot.protocol.StateReduced
import org.pocketbot.protocol.SyncMode
import org.pocketbot.sdk.internal.DEFAULT_SETTINGS_BYTES
import org.pocketbot.sdk.internal.EMPTY_STATE
import org.pocketbot.sdk.internal.merge
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport
import org.pocketbot.sdk.transport.TransportLostException
import kotlin.coroutines.ContinuationInterceptor
import kotlin.coroutines.CoroutineContext
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * Connects to this robot: opens the link, exchanges `hello_request`/`hello`, checks that the firmware speaks this
 * SDK's protocol, learns the settings (from [RobotOptions.settingsCache] when the robot is known, else with
 * `read_settings`) and asks for state in [RobotOptions.syncMode]. Suspends until all that is done.
 *
 * The robot's coroutines are children of [scope] (cancelling it closes the robot); without a scope the robot owns
 * its own, and [Robot.close] ends it.
 *
 * ```
 * val robot = discoverer.discover().first().connect()
 * robot.locomotion.enqueue(Movement.Straight(distanceM = 0.10, speedMps = 0.2)).await()
 * robot.close()
 * ```
 *
 * @throws ProtocolMismatchException when the firmware speaks another protocol version or layout.
 * @throws ConnectFailedException when the robot cannot be reached or does not answer.
 */
public suspend fun RobotDevice.connect(scope: CoroutineScope? = null, options: RobotOptions = RobotOptions()): Robot {
    val robot = Robot(this, scope, options)
    try {
        robot.start()
    } catch (e: Throwable) {
        robot.closeWith(e)
        throw e
    }
    return robot
}

/**
 * One connected robot: a live mirror of its state and settings, and its modules, 1:1 with the firmware's.
 *
 * Create it with [RobotDevice.connect]. Everything here is safe to use from any thread and coroutine: the robot's
 * own work runs on one serial context (a single-threaded view of [Dispatchers.Default], or of the dispatcher of
 * the scope it was connected in). Suspending functions suspend until the robot acknowledged; they survive link
 * losses (the SDK reconnects and retransmits with the same sequence number, so nothing is executed twice).
 */
public class Robot internal constructor(
    /** The device this robot was connected through; reconnects call its [RobotDevice.open] again. */
    public val device: RobotDevice,
    scope: CoroutineScope?,
    /** The options it was connected with. */
    public val options: RobotOptions,
) : AutoCloseable {
    internal val context: CoroutineContext
    private val job: Job
    internal val scope: CoroutineScope

    init {
        val parent = scope?.coroutineContext
        val dispatcher = parent?.get(ContinuationInterceptor) as? CoroutineDispatcher ?: Dispatchers.Default
        @OptIn(ExperimentalCoroutinesApi::class)
        val serial = dispatcher.limitedParallelism(1)
        job = SupervisorJob(parent?.get(Job))
        context = serial
        this.scope = CoroutineScope(serial + job + CoroutineName("robot ${device.name}"))
    }

    private val _connection = MutableStateFlow<ConnectionState>(ConnectionState.Connecting)
    private val _state = MutableStateFlow(EMPTY_STATE)
    private val _stateUpdates = MutableSharedFlow<StateUpdate>(extraBufferCapacity = 256, onBufferOverflow = BufferOverflow.DROP_OLDEST)
    private val _linkStats = MutableStateFlow(LinkStats())
    private var stats = LinkStats()
    private val closed = CompletableDeferred<Throwable?>()

    /** Where the link stands; says [ConnectionState.Lost] the moment a loss is noticed. */
    public val connection: StateFlow<ConnectionState> = _connection.asStateFlow()

    /**
     * The whole robot state as last reported; `time.timeMs` is the robot time it was measured at. A reduced
     * packet updates encoders, wheel speeds, line position and time and keeps the rest. All zero until the first
     * state packet.
     */
    public val state: StateFlow<RobotState> = _state.asStateFlow()

    /**
     * Every state update, unconflated (a [StateFlow] drops values a slow collector did not see): its kind and the
     * resulting state. Buffers 256 updates, then drops the oldest.
     */
    public val stateUpdates: SharedFlow<StateUpdate> = _stateUpdates.asSharedFlow()

    /** Link counters: frames received, dropped (corrupt, truncated, unknown), retransmissions, reconnects. */
    public val linkStats: StateFlow<LinkStats> = _linkStats.asStateFlow()

    // StateFlows rather than @Volatile fields: read from any thread, and @Volatile is not common Kotlin for JS.
    private val _identity = MutableStateFlow<RobotIdentity?>(null)

    /** Who the robot is, from its `hello`. */
    public val identity: RobotIdentity get() = _identity.value ?: error("robot not connected yet")

    /** Mirror of the settings bytes the robot confirmed; touched only on [context]. */
    private val _settingsBytes = MutableStateFlow(DEFAULT_SETTINGS_BYTES.copyOf())
    internal var settingsBytes: ByteArray
        get() = _settingsBytes.value
        set(value) {
            _settingsBytes.value = value
        }

    /** Debug text from the firmware and warnings of the SDK about this link. */
    public val debugLog: DebugLog = DebugLog()

    /** State reflection: sync mode and period. */
    public val reflector: StateReflector = StateReflector(this)

    /** Typed tree of every setting, e.g. `robot.settings.linePid.kp.set(1.5f)`. */
    public val settings: RobotSettings = RobotSettings(this)

    /** Movement queue (straight, rotate, arc), stop, and teleoperation. */
    public val locomotion: Locomotion = Locomotion(this)

    /** The eight-spot line sensor. */
    public val lineSensor: LineSensor = LineSensor()

    /** Line following in the firmware. */
    public val lineFollower: LineFollower = LineFollower(this)

    /** IR proximity: encounters with other robots and obstacles, and IR messages. */
    public val proximity: Proximity = Proximity(this)

    /** The colour sensor under the robot. */
    public val colour: ColourSensor = ColourSensor()

    /** The accelerometer. */
    public val accelerometer: Accelerometer = Accelerometer()

    /** Battery, current and MCU temperature. */
    public val power: Power = Power()

    /** Wheel speeds and motor PWM. */
    public val motors: Motors = Motors()

    /** Dead-reckoned pose from the encoders (thesis 9.8). */
    public val odometry: Odometry = Odometry(this)

    // ---- link machinery (only on [context]) ----

    private inner class Session(val transport: Transport) {
        // Time in heartbeat ticks, not wall-clock marks: follows the dispatcher's clock (virtual time in tests).
        var tick = 0L
        var lastRx = 0L
        var lastTx = 0L
        val ended = CompletableDeferred<Unit>()
        val jobs = ArrayList<Job>()
    }

    internal class Pending(val seq: Int, val packet: Packet) {
        val frame: ByteArray = Frames.encode(packet, seq)
        val done = CompletableDeferred<Unit>()
        var sentIn: Any? = null
    }

    private var current: Session? = null
    private val pending = HashMap<Int, Pending>()
    private var inFlight: Pending? = null
    private val commandMutex = Mutex()
    private var lastSeq = 0
    private var helloWaiter: CompletableDeferred<Hello>? = null
    private var readBuffer: ByteArray? = null
    private var readCoverage: BooleanArray? = null

    private val closing: Boolean get() = closed.isCompleted

    internal suspend fun start(): Unit = withContext(context) {
        val session = try {
            openSession(first = true)
        } catch (e: ProtocolMismatchException) {
            throw e
        } catch (e: CancellationException) {
            throw e
        } catch (e: Throwable) {
            throw ConnectFailedException("cannot connect to ${device.name} at ${device.address}: ${e.message}", e)
        }
        scope.launch { supervise(session) }
    }

    private suspend fun openSession(first: Boolean): Session {
        val transport = device.open()
        val session = Session(transport)
        current = session
        session.jobs += scope.launch { readLoop(session) }
        try {
            handshake(session)
            if (first) learnSettings(session)
            // The command in flight goes first: the robot re-acks it if it already executed it (it remembers the
            // last few sequence numbers), so a movement is never executed twice, and nothing overtakes it.
            inFlight?.let { p ->
                stats = stats.copy(retransmissions = stats.retransmissions + 1)
                send(session, p)
            }
            rawCommand(session, reflector.desiredPacket(), options.commandTimeout, options.commandRetries)
            reflector.confirmed()
        } catch (e: Throwable) {
            endSession(session, "handshake failed: ${e.message}")
            throw e
        }
        session.jobs += scope.launch { heartbeatLoop(session) }
        _connection.value = ConnectionState.Connected
        return session
    }

    private suspend fun handshake(session: Session) {
        val waiter = CompletableDeferred<Hello>()
        helloWaiter = waiter
        try {
            var hello: Hello? = null
            for (attempt in 1..options.helloAttempts) {
                send(session, HelloRequest(ProtocolInfo.VERSION), 0)
                hello = withTimeoutOrNull(options.helloTimeout) { select<Hello?> { waiter.onAwait { it }; session.ended.onAwait { null } } }
                if (hello != null || session.ended.isCompleted) break
            }
            if (session.ended.isCompleted) throw TransportLostException("link lost during the handshake")
            hello ?: throw RobotException("no hello after ${options.helloAttempts} hello_request(s)")
            if (hello.protocolVersion != ProtocolInfo.VERSION || hello.layoutHash != ProtocolInfo.LAYOUT_HASH) {
                throw ProtocolMismatchException(hello.protocolVersion, hello.layoutHash, ProtocolInfo.VERSION, ProtocolInfo.LAYOUT_HASH)
            }
            _identity.value = identityOf(hello, session.transport.address)
        } finally {
            helloWaiter = null
        }
    }

    private suspend fun learnSettings(session: Session) {
        val cached = options.settingsCache?.get(cacheKey)
        if (cached != null && cached.size == ProtocolInfo.SETTINGS_SIZE) {
            settingsChanged(cached)
            debugLog.host(2, "settings of robot ${identity.robotId} taken from the cache")
            return
        }
        readSettings { rawCommand(session, ReadSettings, options.settingsReadTimeout, 2) }
    }

    internal val cacheKey: SettingsCacheKey
        get() = SettingsCacheKey(identity.robotId, identity.layoutHash)

    /** Runs one `read_settings` through [exchange], retrying until every byte arrived; updates the mirror. */
    internal suspend fun readSettings(exchange: suspend () -> Unit): ByteArray = withContext(context) {
        repeat(3) {
            val buffer = ByteArray(ProtocolInfo.SETTINGS_SIZE)
            val coverage = BooleanArray(ProtocolInfo.SETTINGS_SIZE)
            readBuffer = buffer
            readCoverage = coverage
            try {
                exchange()
            } finally {
                readBuffer = null
                readCoverage = null
            }
            if (coverage.all { it }) {
                settingsChanged(buffer)
                options.settingsCache?.put(cacheKey, buffer)
                return@withContext buffer
            }
            debugLog.host(1, "settings read incomplete (${coverage.count { !it }} bytes missing), reading again")
        }
        throw RobotException("settings could not be read completely")
    }

    internal fun settingsChanged(bytes: ByteArray) {
        settingsBytes = bytes.copyOf()
        settings.mirrorChanged(settingsBytes)
    }

    /** Writes [data] at [offset] into the confirmed mirror (after the robot acked it) and the cache. */
    internal suspend fun settingsWritten(offset: Int, data: ByteArray) {
        val copy = settingsBytes.copyOf()
        data.copyInto(copy, offset)
        settingsChanged(copy)
        options.settingsCache?.put(cacheKey, copy)
    }

    private suspend fun supervise(first: Session) {
        var session = first
        while (true) {
            session.ended.await()
            if (closing) return
            var attempt = 0
            while (true) {
                attempt++
                if (attempt > options.reconnect.maxAttempts) {
                    closeWith(RobotClosedException("gave up reconnecting to ${device.name} after ${attempt - 1} attempts"))
                    return
                }
                delay(options.reconnect.delayBefore(attempt))
                if (closing) return
                _connection.value = ConnectionState.Reconnecting(attempt)
                try {
                    session = openSession(first = false)
                    stats = stats.copy(reconnects = stats.reconnects + 1)
                    publishStats()
                    debugLog.host(2, "reconnected to ${device.name} (attempt $attempt)")
                    break
                } catch (e: ProtocolMismatchException) {
                    closeWith(e)
                    return
                } catch (e: CancellationException) {
                    throw e
                } catch (e: Throwable) {
                    debugLog.host(1, "reconnect attempt $attempt failed: ${e.message}")
                    if (!closing) _connection.value = ConnectionState.Lost("reconnect attempt $attempt failed: ${e.message}")
                }
            }
        }
    }

    private suspend fun readLoop(session: Session) {
        val reason = try {
            for (frame in session.transport.incoming) {
                session.lastRx = session.tick
                handleFrame(frame)
            }
            "link closed"
        } catch (e: CancellationException) {
            throw e
        } catch (e: Throwable) {
            e.message ?: e.toString()
        }
        endSession(session, reason)
    }

    private suspend fun heartbeatLoop(session: Session) {
        val step = 25.milliseconds
        while (!session.ended.isCompleted) {
            val period = options.heartbeatPeriod ?: run {
                val failsafe = settings.link.failsafeTimeoutMs.value
                if (failsafe == 0) 1000.milliseconds else minOf(1000, maxOf(30, failsafe / 3)).milliseconds
            }
            delay(step)
            session.tick++
            if (step * (session.tick - session.lastTx).toInt() >= period) {
                try {
                    send(session, Heartbeat, 0)
                } catch (e: TransportLostException) {
                    endSession(session, e.message ?: "send failed")
                    return
                }
            }
            val silence = maxOf(options.silenceTimeout, reflector.period.value * 3)
            if (reflector.mode.value != SyncMode.NONE && step * (session.tick - session.lastRx).toInt() > silence) {
                endSession(session, "nothing received for $silence")
                return
            }
        }
    }

    private fun endSession(session: Session, reason: String) {
        if (session.ended.isCompleted) return
        session.ended.complete(Unit)
        session.transport.close()
        if (current === session) current = null
        session.jobs.forEach { it.cancel() }
        if (!closing) {
            _connection.value = ConnectionState.Lost(reason)
            debugLog.host(1, "link to ${device.name} lost: $reason")
        }
    }

    // ---- incoming ----

    private fun handleFrame(frame: ByteArray) {
        stats = stats.copy(framesReceived = stats.framesReceived + 1)
        when (val result = Frames.decode(frame)) {
            is FrameResult.Failed -> dropped(result.error)
            is FrameResult.Decoded -> dispatch(result.seq, result.packet)
        }
        publishStats()
    }

    private fun dropped(error: ProtocolError) {
        stats = when (error) {
            is ProtocolError.BadCrc -> stats.copy(badCrc = stats.badCrc + 1)
            is ProtocolError.BadLength -> stats.copy(badLength = stats.badLength + 1)
            is ProtocolError.TooShort -> stats.copy(tooShort = stats.tooShort + 1)
            is ProtocolError.TooLong -> stats.copy(tooLong = stats.tooLong + 1)
            is ProtocolError.UnknownType -> stats.copy(unknownType = stats.unknownType + 1)
            is ProtocolError.Framing -> stats.copy(badLength = stats.badLength + 1)
        }
        debugLog.host(1, "dropped frame: ${error.code.name.lowercase()}: ${error.message}")
    }

    private fun dispatch(seq: Int, packet: Packet) {
        when (packet) {
            is StateFull -> {
                stats = stats.copy(fullStates = stats.fullStates + 1)
                applyState(packet.state, StateUpdate.Kind.FULL)
            }
            is StateReduced -> {
                stats = stats.copy(reducedStates = stats.reducedStates + 1)
                applyState(_state.value.merge(packet), StateUpdate.Kind.REDUCED)
            }
            is Ack -> {
                val p = pending[seq]
                if (p != null && p.packet.type == packet.ackedType) p.done.complete(Unit)
                else stats = stats.copy(strayAcks = stats.strayAcks + 1)
            }
            is Error -> {
                val p = pending[packet.seq]
                if (packet.seq != 0 && p != null && p.packet.type == packet.packetType) {
                    stats = stats.copy(refused = stats.refused + 1)
                    p.done.completeExceptionally(CommandRefusedException(packet.packetType, packet.code, packet.detail))
                } else {
                    stats = stats.copy(robotErrors = stats.robotErrors + 1)
                    debugLog.host(1, "robot reported: ${CommandRefusedException(packet.packetType, packet.code, packet.detail).message} (seq ${packet.seq})")
                }
            }
            is SettingsData -> {
                val buffer = readBuffer
                val coverage = readCoverage
                if (buffer == null || coverage == null || packet.offset + packet.data.size > buffer.size) {
                    stats = stats.copy(unexpected = stats.unexpected + 1)
                } else {
                    packet.data.copyInto(buffer, packet.offset)
                    coverage.fill(true, packet.offset, packet.offset + packet.data.size)
                }
            }
            is Hello -> {
                val waiter = helloWaiter
                if (waiter != null) waiter.complete(packet)
                else robotReset(packet)
            }
            is DebugText -> debugLog.robot(packet)
            is IrReceived -> proximity.received(packet)
            is MovementDone -> locomotion.finished(packet.id)
            else -> {
                stats = stats.copy(unexpected = stats.unexpected + 1)
                debugLog.host(1, "unexpected packet from the robot: $packet")
            }
        }
    }

    private fun applyState(state: RobotState, kind: StateUpdate.Kind) {
        _state.value = state
        lineSensor.update(state.line)
        motors.update(state.wheels)
        odometry.update(state.encoders)
        locomotion.update(state.locomotion)
        if (kind == StateUpdate.Kind.FULL) {
            lineFollower.update(state.lineFollow)
            proximity.update(state.proximity, state.time.timeMs)
            colour.update(state.colour)
            accelerometer.update(state.accel)
            power.update(state.power)
        }
        _stateUpdates.tryEmit(StateUpdate(kind, state))
    }

    private fun robotReset(hello: Hello) {
        debugLog.host(1, "robot ${hello.robotId} announced itself unasked (reset?); re-sending the sync mode")
        _identity.value = identityOf(hello, _identity.value?.address ?: device.address)
        val session = current ?: return
        scope.launch {
            try {
                rawCommand(session, reflector.desiredPacket(), options.commandTimeout, options.commandRetries)
            } catch (e: CancellationException) {
                throw e
            } catch (e: Throwable) {
                debugLog.host(1, "re-sending the sync mode failed: ${e.message}")
            }
        }
    }

    private fun publishStats() {
        _linkStats.value = stats
    }

    // ---- outgoing ----

    private fun nextSeq(): Int {
        do {
            lastSeq = lastSeq % 255 + 1
        } while (pending.containsKey(lastSeq))
        return lastSeq
    }

    private suspend fun send(session: Session, packet: Packet, seq: Int) {
        session.transport.send(Frames.encode(packet, seq))
        session.lastTx = session.tick
        stats = stats.copy(framesSent = stats.framesSent + 1)
    }

    private suspend fun send(session: Session, p: Pending) {
        p.sentIn = session
        session.transport.send(p.frame)
        session.lastTx = session.tick
        stats = stats.copy(framesSent = stats.framesSent + 1)
    }

    /** An acknowledged command on [session] outside the command queue (handshake only). */
    private suspend fun rawCommand(session: Session, packet: Packet, timeout: Duration, retries: Int) {
        val p = Pending(nextSeq(), packet)
        pending[p.seq] = p
        try {
            for (attempt in 0..retries) {
                if (attempt > 0) stats = stats.copy(retransmissions = stats.retransmissions + 1)
                send(session, p)
                val ok = withTimeoutOrNull(timeout) {
                    select<Boolean> { p.done.onAwait { true }; session.ended.onAwait { false } }
                } ?: continue
                if (!ok) throw TransportLostException("link lost while waiting for the ack of ${packet::class.simpleName}")
                return
            }
            throw CommandTimeoutException(packet.type, retries + 1)
        } finally {
            pending.remove(p.seq)
        }
    }

    /**
     * Sends an acknowledged command and suspends until the robot acked it. One command is in flight at a time, so
     * the robot executes commands in the order they were issued. A timeout on a live link retransmits with the same
     * sequence number; a link loss waits for the reconnect, which retransmits first. [beforeFirstSend] runs once
     * the command is ready to go (used to start movements on several robots at the same moment).
     *
     * @throws CommandRefusedException when the robot answers with `error`.
     */
    internal suspend fun command(packet: Packet, beforeFirstSend: (suspend () -> Unit)? = null): Unit = withContext(context) {
        commandMutex.withLock {
            if (closing) throw RobotClosedException("robot ${device.name} is closed")
            val p = Pending(nextSeq(), packet)
            pending[p.seq] = p
            inFlight = p
            try {
                var retries = 0
                var gate = beforeFirstSend
                while (true) {
                    val session = awaitSession()
                    if (gate != null) {
                        gate()
                        gate = null
                        continue
                    }
                    if (p.sentIn !== session) {
                        try {
                            send(session, p)
                        } catch (e: TransportLostException) {
                            endSession(session, e.message ?: "send failed")
                            continue
                        }
                    }
                    val outcome = withTimeoutOrNull(options.commandTimeout) {
                        select<Boolean> {
                            p.done.onAwait { true }
                            closed.onAwait { false }
                        }
                    }
                    if (outcome == true) {
                        publishStats()
                        return@withLock
                    }
                    if (outcome == false) throw RobotClosedException("robot ${device.name} closed while waiting for an ack")
                    if (current === session && !session.ended.isCompleted) {
                        retries++
                        if (retries > options.commandRetries) throw CommandTimeoutException(packet.type, retries)
                        stats = stats.copy(retransmissions = stats.retransmissions + 1)
                        p.sentIn = null
                    }
                }
            } finally {
                pending.remove(p.seq)
                if (inFlight === p) inFlight = null
            }
        }
    }

    /** Sends an unacknowledged packet (teleoperation) if the link is up; returns false when it is not. */
    internal suspend fun sendUnacked(packet: Packet): Boolean = withContext(context) {
        val session = current
        if (session == null || _connection.value != ConnectionState.Connected) return@withContext false
        try {
            send(session, packet, 0)
            true
        } catch (e: TransportLostException) {
            endSession(session, e.message ?: "send failed")
            false
        }
    }

    private suspend fun awaitSession(): Session {
        while (true) {
            val s = _connection.first { it is ConnectionState.Connected || it is ConnectionState.Closed }
            if (s is ConnectionState.Closed) throw RobotClosedException("robot ${device.name} is closed", s.cause)
            current?.let { return it }
        }
    }

    /** Suspends until [deferred] completes or the robot closes. */
    internal suspend fun <T> awaitOrClosed(deferred: CompletableDeferred<T>): T = select {
        deferred.onAwait { it }
        closed.onAwait { throw RobotClosedException("robot ${device.name} is closed", it) }
    }

    /** Runs [block] on the robot's serial context. */
    internal suspend fun <T> serial(block: suspend () -> T): T = withContext(context) { block() }

    /**
     * Closes the link and ends the robot's coroutines; idempotent. Commands still waiting fail with
     * [RobotClosedException]. Safe to call from any thread.
     */
    override fun close() {
        closeWith(null)
    }

    internal fun closeWith(cause: Throwable?) {
        if (!closed.complete(cause)) return
        _connection.value = ConnectionState.Closed(cause)
        current?.transport?.close()
        job.cancel()
    }

    override fun toString(): String = "Robot(${_identity.value?.name ?: device.name} at ${device.address}, ${_connection.value})"
}

/**
 * One state update as it arrived.
 *
 * @property kind full or reduced packet.
 * @property state the resulting whole state; `state.time.timeMs` is the robot time of the update.
 */
public class StateUpdate(public val kind: Kind, public val state: RobotState) {
    /** Robot time of this update, in milliseconds since the robot's reset. */
    public val timeMs: Long get() = state.time.timeMs

    /** Which state packet brought the update. */
    public enum class Kind { FULL, REDUCED }

    override fun toString(): String = "StateUpdate($kind at $timeMs ms)"
}

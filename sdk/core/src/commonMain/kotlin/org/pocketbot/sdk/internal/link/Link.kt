package org.pocketbot.sdk.internal.link

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.CompletableJob
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
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
import org.pocketbot.protocol.Driver
import org.pocketbot.protocol.DriverChange as WireChange
import org.pocketbot.protocol.Error
import org.pocketbot.protocol.ErrorCode
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Goodbye
import org.pocketbot.protocol.Heartbeat
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.HostRole
import org.pocketbot.protocol.PACKET_SPECS
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.ProtocolError
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.SetRole
import org.pocketbot.protocol.SettingsData
import org.pocketbot.sdk.CommandRefusedException
import org.pocketbot.sdk.commandName
import org.pocketbot.sdk.CommandTimeoutException
import org.pocketbot.sdk.ConnectFailedException
import org.pocketbot.sdk.ConnectionChange
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.DebugLog
import org.pocketbot.sdk.DriverChange
import org.pocketbot.sdk.Driving
import org.pocketbot.sdk.LinkStats
import org.pocketbot.sdk.NotDriverException
import org.pocketbot.sdk.ProtocolMismatchException
import org.pocketbot.sdk.QueueOnLeave
import org.pocketbot.sdk.RobotClosedException
import org.pocketbot.sdk.RobotEvent
import org.pocketbot.sdk.RobotIdentity
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.Role
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.TransportLostException
import kotlin.coroutines.CoroutineContext
import kotlin.random.Random
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * The link machinery of one robot: it opens sessions on [device], runs the handshake, reads frames, sends
 * heartbeats, notices losses and reconnects, and carries acknowledged commands with sequence numbers,
 * retransmissions and ordering. Everything runs on [context], one coroutine at a time.
 *
 * Two lanes of acknowledged commands: [command] runs one at a time in call order (the robot executes them in the
 * order they were issued), [urgent] (stop) goes out at once, ahead of a command in flight, and first after a
 * reconnect.
 *
 * Every session asks the robot for this host's [Role] right after the hello; the robot tells who drives then and
 * whenever it changes (`driver`), which [driving] and [events] carry. A command that only the driver may send fails
 * at once ([NotDriverException]) while this host watches.
 */
internal class Link(
    val device: RobotDevice,
    override val options: RobotOptions,
    /** A serial view of the SDK's dispatcher: never the caller's. */
    val context: CoroutineContext,
    /** Scope of the robot's own coroutines. */
    private val scope: CoroutineScope,
    private val robotJob: Job,
    /** The robot in its caller's scope: the link's coroutines and the goodbye at [close] run under it. */
    private val lifetime: CompletableJob,
    override val debugLog: DebugLog,
    /** The SDK's random choices for this robot ([org.pocketbot.sdk.RobotRuntime.random]). */
    val random: Random,
) : LinkPort {
    lateinit var client: LinkClient

    /** This host's session id, kept across reconnects so the robot recognises our retransmissions. */
    private val hostSession: Long = random.nextLong(1, 0xFFFF_FFFFL)

    private val _connection = MutableStateFlow<ConnectionState>(ConnectionState.Connecting)
    val connection: StateFlow<ConnectionState> = _connection.asStateFlow()

    private val _changes = MutableSharedFlow<ConnectionChange>(
        extraBufferCapacity = CHANGE_BUFFER, onBufferOverflow = BufferOverflow.DROP_OLDEST,
    )
    val changes: SharedFlow<ConnectionChange> = _changes.asSharedFlow()
    private var changeCount = 0L

    private val stats = MutableLinkStats()
    private val _linkStats = MutableStateFlow(LinkStats.ZERO)
    val linkStats: StateFlow<LinkStats> = _linkStats.asStateFlow()

    private val _identity = MutableStateFlow<RobotIdentity?>(null)
    val identity: StateFlow<RobotIdentity?> = _identity.asStateFlow()

    private val closed = CompletableDeferred<Throwable?>()
    val isClosing: Boolean get() = closed.isCompleted

    /** What this host asks for at the next handshake: after a take-over, to drive (not to take it over again). */
    private var role = options.role
    private val _driving = MutableStateFlow(Driving.UNKNOWN)
    val driving: StateFlow<Driving> = _driving.asStateFlow()
    private val _events = MutableSharedFlow<RobotEvent>(extraBufferCapacity = CHANGE_BUFFER, onBufferOverflow = BufferOverflow.DROP_OLDEST)
    val events: SharedFlow<RobotEvent> = _events.asSharedFlow()
    private var driverWaiter: CompletableDeferred<Driver>? = null

    /** Set when what connects this host to the robot said that no link of it is free (`no_free_link`). */
    private var noFreeLink: Int? = null

    private val table = CommandTable()
    private val order = Mutex()
    private var inFlight: PendingCommand? = null
    private val urgentWaiting = ArrayList<PendingCommand>()
    private var current: Session? = null
    private var helloWaiter: CompletableDeferred<Hello>? = null
    private var helloSeq = 0

    override var settingsSink: ((SettingsData) -> Boolean)? = null

    // ---- lifecycle ----

    /** Opens the first session: suspends until the handshake and the restore are done. */
    suspend fun start(): Unit = withContext(context) {
        val session = try {
            openSession(first = true)
        } catch (e: ProtocolMismatchException) {
            throw e
        } catch (e: CancellationException) {
            throw e
        } catch (e: Throwable) {
            // Transports begin their messages with the address: say it once.
            val where = if (device.name == device.address) device.address else "${device.name} at ${device.address}"
            throw ConnectFailedException("cannot connect to $where: ${e.message?.removePrefix("${device.address}: ")}", e)
        }
        scope.launch { supervise(session) }
    }

    private suspend fun openSession(first: Boolean): Session {
        val session = Session(device.open())
        current = session
        session.jobs += scope.launch { readLoop(session) }
        session.jobs += scope.launch { countTransportDrops(session) }
        try {
            val hello = handshake(session)
            val driver = claim(session)
            // A stop issued while the link was down goes out before anything else.
            for (p in urgentWaiting.toList()) if (!p.answer.isCompleted) exchange(session, p)
            client.restore(hello, first, driver) { exchange(session, table.open(it), closeAfter = true) }
            resendInFlight(session)
        } catch (e: Throwable) {
            endSession(session, "handshake failed: ${e.message}")
            throw e
        }
        session.jobs += scope.launch { heartbeatLoop(session) }
        setConnection(ConnectionState.Connected)
        return session
    }

    /**
     * Asks the robot for this host's role (`set_role`, under [RobotOptions.hostLabel]) and returns its answer: the
     * `driver` packet it sends before the ack.
     */
    private suspend fun claim(session: Session): Driver {
        val waiter = CompletableDeferred<Driver>()
        driverWaiter = waiter
        try {
            exchange(session, table.open(SetRole(role.wire(), label())), closeAfter = true)
        } finally {
            driverWaiter = null
        }
        @OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)
        val driver = if (waiter.isCompleted) waiter.getCompleted() else throw RobotClosedException("the robot acknowledged set_role without saying who drives")
        if (role == Role.TAKE_OVER) role = Role.DRIVE
        return driver
    }

    /**
     * Asks for [wanted] on the live session as an ordinary command and returns who drives after the robot's answer.
     * The answer counts for later reconnects too.
     */
    suspend fun requestRole(wanted: Role): Driving {
        role = wanted
        command(SetRole(wanted.wire(), label()))
        return serial {
            if (role == Role.TAKE_OVER) role = Role.DRIVE
            _driving.value
        }
    }

    /** [RobotOptions.hostLabel] as the robot keeps it: its first [LABEL_BYTES] bytes of UTF-8, whole characters. */
    private fun label(): String {
        var text = options.hostLabel
        while (text.encodeToByteArray().size > LABEL_BYTES) text = text.dropLast(1)
        return text
    }

    /** The robot told who drives (on its own, or answering): published, and an event when it changed. */
    private fun driverSaid(p: Driver) {
        val before = _driving.value
        val now = Driving(p.role == HostRole.DRIVE.code, p.label.ifEmpty { null }, changeOf(p.change))
        driverWaiter?.complete(p)
        if (now == before) return
        _driving.value = now
        if (now.byThisHost != before.byThisHost || now.driver != before.driver) {
            val taken = before.byThisHost && !now.byThisHost && now.driver != null
            _events.tryEmit(RobotEvent.DriverChanged(now, taken))
            debugLog.host(if (taken) 1 else 2, "${device.name}: $now" + if (taken) " (taken from this host)" else "")
        }
    }

    /** Tells the robot's user of [event] ([events]). */
    fun emit(event: RobotEvent) {
        _events.tryEmit(event)
    }

    /** Fails [packet] at once while this host watches and only the driver may send it. */
    private fun checkDriving(packet: Packet) {
        notDriver(packet)?.let { throw it }
    }

    /** Why this host may not send [packet] now (it watches, and only the driver may), or null when it may. */
    private fun notDriver(packet: Packet): NotDriverException? {
        val d = _driving.value
        if (d.byThisHost || PACKET_SPECS[packet.type]?.watcherOk == true) return null
        return notDriver(packet.type, d.driver)
    }

    private fun notDriver(packetType: Int, driver: String?) =
        NotDriverException(identity.value?.name ?: device.name, commandName(packetType), driver)

    /**
     * Says goodbye: the robot finishes or drops what this host queued ([queue]), and does not take the closing link
     * for a lost one. Suspends until the robot acknowledged it, at most a few command timeouts; false when it did
     * not (no link, no answer): then its failsafe stops what this host drove.
     */
    suspend fun leave(queue: QueueOnLeave): Boolean = withContext(context) {
        val session = current?.takeIf { it.isLive && _connection.value == ConnectionState.Connected } ?: return@withContext false
        val p = table.open(Goodbye(queue.ordinal))
        try {
            exchange(session, p, closeAfter = true)
            true
        } catch (e: CancellationException) {
            throw e
        } catch (e: Throwable) {
            debugLog.host(1, "goodbye to ${device.name} not acknowledged: ${e.message}")
            false
        }
    }

    /** The command in flight at the loss: sent again with its sequence number unless the robot already holds it. */
    private suspend fun resendInFlight(session: Session) {
        val p = inFlight ?: return
        if (p.answer.isCompleted || !p.wanted()) return
        notDriver(p.packet)?.let {
            p.answer.completeExceptionally(it)
            return
        }
        if (p.everSent && client.alreadyHeld(p.packet)) {
            p.answer.complete(Unit)
            return
        }
        if (p.everSent) stats.retransmissions++
        send(session, p)
    }

    private suspend fun handshake(session: Session): Hello {
        val waiter = CompletableDeferred<Hello>()
        helloWaiter = waiter
        try {
            var hello: Hello? = null
            for (attempt in 1..options.helloAttempts) {
                // The answer carries this number: a hello with another (0: sent at reset) answers nothing of ours.
                helloSeq = helloSeq % 255 + 1
                send(session, HelloRequest(ProtocolInfo.VERSION, hostSession), helloSeq)
                hello = withTimeoutOrNull(options.helloTimeout) {
                    select<Hello?> { waiter.onAwait { it }; session.ended.onAwait { null } }
                }
                if (hello != null || !session.isLive) break
            }
            noFreeLink?.let { throw TransportLostException("all $it host links of ${device.name} are in use by other hosts") }
            if (!session.isLive) throw TransportLostException("link lost during the handshake")
            // A live link that never answers is a timeout (ConnectFailedException carries it as the cause).
            hello ?: throw CommandTimeoutException("hello_request", options.helloAttempts)
            if (hello.protocolVersion != ProtocolInfo.VERSION || hello.layoutHash != ProtocolInfo.LAYOUT_HASH) {
                throw ProtocolMismatchException(hello.protocolVersion, hello.layoutHash, ProtocolInfo.VERSION, ProtocolInfo.LAYOUT_HASH)
            }
            _identity.value = RobotIdentity.of(hello, session.transport.address)
            return hello
        } finally {
            helloWaiter = null
        }
    }

    private suspend fun supervise(first: Session) {
        var session = first
        while (true) {
            session.ended.await()
            if (isClosing) return
            var attempt = 0
            var waited = Duration.ZERO
            var wait: Duration? = null
            while (true) {
                attempt++
                if (attempt > options.reconnect.maxAttempts) {
                    close(RobotClosedException("gave up reconnecting to ${device.name} after ${attempt - 1} attempts"))
                    return
                }
                // Quick retries while the robot's failsafe has not stopped it yet, then a growing wait.
                wait = options.reconnect.nextDelay(waited, wait).also { waited += it }
                delay(wait)
                if (isClosing) return
                setConnection(ConnectionState.Reconnecting(attempt))
                try {
                    session = openSession(first = false)
                    stats.reconnects++
                    publishStats()
                    debugLog.host(2, "reconnected to ${device.name} (attempt $attempt)")
                    break
                } catch (e: ProtocolMismatchException) {
                    close(e)
                    return
                } catch (e: CancellationException) {
                    throw e
                } catch (e: Throwable) {
                    // A line per attempt would be dozens a second while the retries are quick: the first, then ever rarer.
                    if (attempt and (attempt - 1) == 0) debugLog.host(1, "reconnect attempt $attempt failed: ${e.message}")
                    if (!isClosing) setConnection(ConnectionState.Lost("reconnect attempt $attempt failed: ${e.message}"))
                }
            }
        }
    }

    private suspend fun readLoop(session: Session) {
        val reason = try {
            for (frame in session.transport.incoming) {
                session.received = true
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

    private suspend fun countTransportDrops(session: Session) {
        var seen = session.transport.droppedFrames.value
        session.transport.droppedFrames.collect { now ->
            stats.tooLong += now.tooLong - seen.tooLong
            stats.badFraming += now.badFraming - seen.badFraming
            if (now.tooLong != seen.tooLong || now.badFraming != seen.badFraming) {
                debugLog.host(1, "the transport dropped ${now.total - seen.total} broken frame(s)")
                publishStats()
                client.onFrameDropped()
            }
            seen = now
        }
    }

    /**
     * Wakes every half heartbeat period (or quarter silence timeout): a heartbeat goes out when nothing else did since
     * the last wake, so the link is never quiet for a whole period; the link counts as lost once nothing arrived for
     * longer than the silence timeout (noticed within one wake of it).
     */
    private suspend fun heartbeatLoop(session: Session) {
        while (session.isLive) {
            val silence = client.silenceTimeout
            val wake = (client.heartbeatPeriod / 2).let { if (silence == null) it else minOf(it, silence / 4) }
            delay(wake)
            val sentSince = session.sent
            session.sent = false
            if (!sentSince) {
                try {
                    send(session, Heartbeat, 0) // marks the session as sent: the next wake lets it be
                } catch (e: TransportLostException) {
                    endSession(session, e.message ?: "send failed")
                    return
                }
            }
            session.quiet = if (session.received) Duration.ZERO else session.quiet + wake
            session.received = false
            if (silence != null && session.quiet > silence) {
                endSession(session, "nothing received for $silence")
                return
            }
        }
    }

    private fun endSession(session: Session, reason: String) {
        if (!session.ended.complete(reason)) return
        session.transport.close()
        if (current === session) current = null
        session.jobs.forEach { it.cancel() }
        if (!isClosing) {
            setConnection(ConnectionState.Lost(reason))
            debugLog.host(1, "link to ${device.name} lost: $reason")
        }
    }

    private fun setConnection(state: ConnectionState) {
        if (_connection.value == state) return
        _connection.value = state
        _changes.tryEmit(ConnectionChange(++changeCount, state))
    }

    /**
     * Closes the link and ends the robot's coroutines; idempotent, from any thread. With [goodbye] a live link first
     * carries a `goodbye` (the queue finishes), without waiting for its ack: the transport closes once it is sent.
     */
    fun close(cause: Throwable?, goodbye: Boolean = false) {
        if (!closed.complete(cause)) return
        val connected = _connection.value == ConnectionState.Connected
        setConnection(ConnectionState.Closed(cause))
        val transport = current?.transport
        if (goodbye && connected && transport != null) {
            // Beside the link's coroutines, which end now; bounded by a command timeout. The caller's scope waits for it.
            CoroutineScope(context + lifetime).launch {
                try {
                    withTimeoutOrNull(options.commandTimeout) { transport.send(table.open(Goodbye(QueueOnLeave.FINISH.ordinal)).frame) }
                } catch (e: Throwable) {
                    // Gone already: the robot's failsafe stops what this host drove.
                }
            }.invokeOnCompletion { transport.close() } // also when the scope was cancelled before it ran
        } else {
            transport?.close()
        }
        robotJob.cancel()
        lifetime.complete()
    }

    // ---- incoming ----

    private fun handleFrame(frame: ByteArray) {
        stats.framesReceived++
        when (val result = Frames.decode(frame)) {
            is FrameResult.Failed -> {
                dropped(result.error)
                publishStats()
            }
            is FrameResult.Decoded -> dispatch(result.seq, result.packet)
        }
    }

    private fun dropped(error: ProtocolError) {
        when (error) {
            is ProtocolError.BadCrc -> stats.badCrc++
            is ProtocolError.BadLength -> stats.badLength++
            is ProtocolError.TooShort -> stats.tooShort++
            is ProtocolError.TooLong -> stats.tooLong++
            is ProtocolError.UnknownType -> stats.unknownType++
            is ProtocolError.Framing -> stats.badFraming++
        }
        debugLog.host(1, "dropped frame: ${error.code.name.lowercase()}: ${error.message}")
        client.onFrameDropped()
    }

    private fun dispatch(seq: Int, packet: Packet) {
        when (packet) {
            is Ack -> {
                val p = table.find(seq, packet.ackedType)
                if (p != null) p.answer.complete(Unit) else stats.strayAcks++
            }
            is Error -> {
                val p = if (packet.seq != 0) table.find(packet.seq, packet.packetType) else null
                val refusal = if (packet.code == ErrorCode.NOT_DRIVER.code) {
                    val d = _driving.value // told just before, unless that was lost
                    notDriver(packet.packetType, d.driver.takeIf { !d.byThisHost })
                } else {
                    CommandRefusedException(packet.packetType, packet.code, packet.detail)
                }
                if (packet.code == ErrorCode.NO_FREE_LINK.code) noFreeLink = packet.detail
                if (p != null) {
                    stats.refused++
                    p.answer.completeExceptionally(refusal)
                } else {
                    stats.robotErrors++
                    debugLog.host(1, "robot reported: ${refusal.message} (seq ${packet.seq})")
                }
            }
            is SettingsData -> if (settingsSink?.invoke(packet) != true) stats.unexpected++
            is Driver -> driverSaid(packet)
            is Hello -> when {
                helloWaiter != null -> if (seq == helloSeq) helloWaiter?.complete(packet)
                seq == 0 -> robotReset(packet)
                else -> stats.unexpected++ // a late answer to an earlier hello_request
            }
            else -> {
                if (packet is org.pocketbot.protocol.StateFull) stats.fullStates++
                if (packet is org.pocketbot.protocol.StateReduced) stats.reducedStates++
                // Counted before the packet takes effect: whoever sees a state also sees it counted (a tuning chart's
                // "charted of sent" never runs ahead of the link's own count).
                publishStats()
                client.onPacket(packet)
                return
            }
        }
        publishStats()
    }

    /**
     * The robot announced itself at reset: it lost its queue, its log and our session. That is a lost link as far as
     * the host is concerned: the session ends and the reconnect runs the whole handshake and restore again, in
     * order, before commands flow. A storm of such hellos costs one reconnect per hello, with the usual backoff.
     */
    private fun robotReset(hello: Hello) {
        val session = current ?: return
        debugLog.host(1, "robot ${hello.robotId} was reset (it said hello unasked)")
        endSession(session, "the robot was reset")
    }

    // ---- outgoing ----

    private suspend fun send(session: Session, packet: Packet, seq: Int) {
        session.transport.send(Frames.encode(packet, seq))
        session.sent = true
        stats.framesSent++
    }

    private suspend fun send(session: Session, p: PendingCommand) {
        p.sentIn = session
        p.everSent = true
        session.transport.send(p.frame)
        session.sent = true
        stats.framesSent++
    }

    /** Runs [p] on [session] outside the command lanes (handshake steps, restore): retries, then gives up. */
    private suspend fun exchange(session: Session, p: PendingCommand, closeAfter: Boolean = false) {
        try {
            for (attempt in 0..options.commandRetries) {
                if (attempt > 0) stats.retransmissions++
                send(session, p)
                val ok = withTimeoutOrNull(options.commandTimeout) {
                    select<Boolean> { p.answer.onAwait { true }; session.ended.onAwait { false } }
                } ?: continue
                if (!ok) throw TransportLostException("link lost while waiting for the ack of ${p.packet::class.simpleName}")
                return
            }
            throw CommandTimeoutException(p.packet.type, options.commandRetries + 1)
        } finally {
            if (closeAfter) table.close(p)
        }
    }

    /**
     * Sends an acknowledged command and suspends until the robot acked it. One command is in flight at a time, so
     * the robot executes them in call order. A timeout on a live link retransmits with the same sequence number; a
     * loss waits for the reconnect, which sends it again unless the robot already holds it. [wanted] is asked before
     * every transmission: once it says no, the command is withdrawn ([CommandWithdrawnException]).
     *
     * @throws CommandRefusedException when the robot answers with `error`.
     */
    override suspend fun command(packet: Packet, wanted: () -> Boolean, beforeFirstSend: (suspend () -> Unit)?): Unit =
        withContext(context) {
            order.withLock {
                checkOpen()
                checkDriving(packet)
                if (!wanted()) throw CommandWithdrawnException(everSent = false)
                val p = table.open(packet)
                p.wanted = wanted
                inFlight = p
                try {
                    drive(p, beforeFirstSend)
                } finally {
                    table.close(p)
                    if (inFlight === p) inFlight = null
                }
            }
        }

    private suspend fun drive(p: PendingCommand, beforeFirstSend: (suspend () -> Unit)?) {
        var retries = 0
        var gate = beforeFirstSend
        while (true) {
            val session = awaitSession()
            if (gate != null) {
                // Ready to go: wait for the caller's signal, then look at the link again (it may have changed).
                gate()
                gate = null
                continue
            }
            if (p.sentIn !== session && !p.answer.isCompleted) {
                if (!p.wanted()) throw CommandWithdrawnException(p.everSent)
                if (!p.everSent) checkDriving(p.packet) // the drive may have changed while it waited for the link
                try {
                    send(session, p)
                } catch (e: TransportLostException) {
                    endSession(session, e.message ?: "send failed")
                    continue
                }
            }
            val outcome = withTimeoutOrNull(options.commandTimeout) {
                select<Boolean> { p.answer.onAwait { true }; closed.onAwait { false } }
            }
            if (outcome == true) return publishStats()
            if (outcome == false) throw RobotClosedException("robot ${device.name} closed while waiting for an ack")
            if (current === session && session.isLive) {
                if (++retries > options.commandRetries) throw CommandTimeoutException(p.packet.type, retries)
                stats.retransmissions++
                p.sentIn = null
            }
        }
    }

    /**
     * Sends an acknowledged command ahead of everything: at once on a live link (even while another command waits
     * for its ack), or first of all after the reconnect.
     */
    override suspend fun urgent(packet: Packet): Unit = withContext(context) {
        checkOpen()
        checkDriving(packet)
        val p = table.open(packet)
        urgentWaiting += p
        try {
            var retries = 0
            while (true) {
                val session = current?.takeIf { it.isLive && _connection.value == ConnectionState.Connected }
                if (session != null && p.sentIn !== session && !p.answer.isCompleted) {
                    try {
                        send(session, p)
                    } catch (e: TransportLostException) {
                        endSession(session, e.message ?: "send failed")
                    }
                }
                val outcome = withTimeoutOrNull(options.commandTimeout) {
                    select<Boolean> { p.answer.onAwait { true }; closed.onAwait { false } }
                }
                if (outcome == true) return@withContext publishStats()
                if (outcome == false) throw RobotClosedException("robot ${device.name} closed while waiting for an ack")
                if (session != null && current === session && session.isLive) {
                    if (++retries > options.commandRetries) throw CommandTimeoutException(packet.type, retries)
                    stats.retransmissions++
                    p.sentIn = null
                }
            }
        } finally {
            urgentWaiting.remove(p)
            table.close(p)
        }
    }

    /** Sends an unacknowledged packet if the link is up; false when it is not. */
    override suspend fun sendUnacked(packet: Packet): Boolean = withContext(context) {
        checkDriving(packet)
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

    private fun checkOpen() {
        if (isClosing) throw RobotClosedException("robot ${device.name} is closed")
    }

    /** Starts [block] among the robot's own coroutines. */
    override fun launch(block: suspend () -> Unit): Job = scope.launch { block() }

    /** Runs [block] on the link's serial context. */
    override suspend fun <T> serial(block: suspend () -> T): T = withContext(context) { block() }

    /** Suspends until [deferred] completes or the robot closes. */
    override suspend fun <T> awaitOrClosed(deferred: CompletableDeferred<T>): T = select {
        deferred.onAwait { it }
        closed.onAwait { throw RobotClosedException("robot ${device.name} is closed", it) }
    }

    fun noteUnexpected() {
        stats.unexpected++
    }

    private fun publishStats() {
        _linkStats.value = stats.snapshot()
    }

    companion object {
        const val CHANGE_BUFFER: Int = 256

        /** The robot keeps this many bytes of a host's label. */
        const val LABEL_BYTES: Int = 16

        private fun Role.wire(): Int = when (this) {
            Role.WATCH -> HostRole.WATCH.code
            Role.DRIVE -> HostRole.DRIVE.code
            Role.TAKE_OVER -> HostRole.TAKE_OVER.code
        }

        private fun changeOf(code: Int): DriverChange = when (code) {
            WireChange.CLAIMED.code -> DriverChange.CLAIMED
            WireChange.TAKEN_OVER.code -> DriverChange.TAKEN_OVER
            WireChange.LEFT.code -> DriverChange.LEFT
            WireChange.LOST.code -> DriverChange.LOST
            else -> DriverChange.NONE
        }
    }
}

/** A command withdrawn before the robot acked it (by a stop); [everSent] says whether the robot may hold it. */
internal class CommandWithdrawnException(val everSent: Boolean) : RuntimeException("withdrawn by a stop")

/** The link's counters while they change; published as immutable [LinkStats]. */
internal class MutableLinkStats {
    var framesReceived = 0L
    var framesSent = 0L
    var fullStates = 0L
    var reducedStates = 0L
    var badCrc = 0L
    var badLength = 0L
    var tooShort = 0L
    var tooLong = 0L
    var badFraming = 0L
    var unknownType = 0L
    var unexpected = 0L
    var strayAcks = 0L
    var retransmissions = 0L
    var refused = 0L
    var robotErrors = 0L
    var reconnects = 0L

    fun snapshot(): LinkStats = LinkStats(
        framesReceived, framesSent, fullStates, reducedStates, badCrc, badLength, tooShort, tooLong, badFraming,
        unknownType, unexpected, strayAcks, retransmissions, refused, robotErrors, reconnects,
    )
}

package org.pocketbot.sdk

import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.CompletableJob
import kotlinx.coroutines.CoroutineName
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.ExperimentalCoroutinesApi
import kotlinx.coroutines.Job
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.awaitCancellation
import kotlinx.coroutines.launch
import kotlinx.coroutines.channels.BufferOverflow
import kotlinx.coroutines.flow.MutableSharedFlow
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.SharedFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asSharedFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.withContext
import org.pocketbot.protocol.DebugText
import org.pocketbot.protocol.Driver
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.IrReceived
import org.pocketbot.protocol.MovementDone
import org.pocketbot.protocol.MovementLog
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.StateFull
import org.pocketbot.protocol.StateReduced
import org.pocketbot.sdk.internal.EMPTY_STATE
import org.pocketbot.sdk.internal.SettingsMirror
import org.pocketbot.sdk.internal.link.Link
import org.pocketbot.sdk.internal.link.LinkClient
import org.pocketbot.sdk.internal.merge
import org.pocketbot.sdk.transport.RobotDevice
import kotlin.random.Random
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * Connects to this robot: opens the link, exchanges `hello_request`/`hello`, checks that the firmware speaks this
 * SDK's protocol, learns the settings (from [RobotOptions.settingsCache] when the robot's settings checksum matches,
 * else with `read_settings`) and asks for state in [RobotOptions.syncMode]. Suspends until all that is done.
 *
 * The robot belongs to [scope], as a child [Job] of it (as Kable's peripherals and Ktor's clients do): all of its
 * work (reading the link, heartbeats, reconnects) runs under that job, so cancelling the scope closes the robot, and
 * the scope does not complete while the robot is open: [close] it (`use {}`) or [Robot.disconnect] it, and nothing
 * it started outlives the scope. Its work runs on [Dispatchers.Default], never on the caller's thread, unless the
 * scope's context holds a [RobotRuntime].
 *
 * ```
 * runBlocking {
 *     discoverer.discover().first().connect(this).use { robot ->
 *         robot.locomotion.enqueue(Movement.Straight(distanceM = 0.10, speedMps = 0.2)).await()
 *     }
 * }
 * ```
 *
 * @throws ProtocolMismatchException when the firmware speaks another protocol version or layout.
 * @throws ConnectFailedException when the robot cannot be reached or does not answer.
 * @throws IllegalStateException when [scope] has ended already (cancelled or completed).
 */
public suspend fun RobotDevice.connect(scope: CoroutineScope, options: RobotOptions = RobotOptions()): Robot {
    val robot = Robot(this, scope, options)
    check(robot.lifetime.isActive) { "cannot connect ${this.name}: its scope has ended (${scope.coroutineContext[Job]})" }
    try {
        robot.link.start()
    } catch (e: Throwable) {
        robot.link.close(e)
        throw e
    }
    return robot
}

/**
 * One connected robot: a live mirror of its state and settings, and its modules, 1:1 with the firmware's.
 *
 * Create it with [RobotDevice.connect]. Everything here is safe to use from any thread and coroutine. Suspending
 * functions suspend until the robot acknowledged; they survive link losses (the SDK reconnects and retransmits
 * with the same sequence number, so nothing is executed twice). While the link is down the robot's own failsafe
 * may stop it: see [Locomotion] for what that does to queued movements.
 *
 * Several hosts may be connected to one robot; one drives it and the others watch ([driving], [RobotOptions.role]):
 * commands that change the robot fail at once with [NotDriverException] on a host that watches, which may take the
 * robot over ([takeOver]). [events] tells when the drive changes hands and when the robot restarted. [disconnect]
 * says goodbye, so that the robot finishes what this host queued instead of taking it for a lost link.
 */
public class Robot internal constructor(
    /** The device this robot was connected through; reconnects open it again. */
    public val device: RobotDevice,
    scope: CoroutineScope,
    /** The options it was connected with. */
    public val options: RobotOptions,
) : AutoCloseable {
    /** The robot in its caller's scope: a child of the scope's job, complete once all of the robot's work ended. */
    internal val lifetime: CompletableJob
    private val job: CompletableJob
    private val _state = MutableStateFlow(EMPTY_STATE)
    private val _stateUpdates = MutableSharedFlow<StateUpdate>(extraBufferCapacity = 256, onBufferOverflow = BufferOverflow.DROP_OLDEST)
    private val firstFullState = CompletableDeferred<Unit>()

    /** The robot's debug text and the SDK's warnings about its link. */
    public val debugLog: DebugLog = DebugLog()

    internal val link: Link

    init {
        val context = scope.coroutineContext
        val runtime = context[RobotRuntime]
        // One coroutine at a time: the runtime's dispatcher (simulated time), else the device's own event loop
        // (already one thread), else a serial view of Dispatchers.Default.
        @OptIn(ExperimentalCoroutinesApi::class)
        val serial = runtime?.dispatcher?.limitedParallelism(1) ?: device.eventLoop ?: Dispatchers.Default.limitedParallelism(1)
        lifetime = Job(context[Job])
        // The link's coroutines; cancelled at close, while the goodbye still goes out under [lifetime].
        job = SupervisorJob(lifetime)
        val own = CoroutineScope(serial + job + CoroutineName("robot ${device.name}"))
        link = Link(device, options, serial, own, job, lifetime, debugLog, runtime?.random ?: Random.Default)
        // The scope cancelled: the link closes (its transport too, which a read may be waiting on).
        own.launch {
            try {
                awaitCancellation()
            } finally {
                link.close(RobotClosedException("the scope of robot ${device.name} ended"))
            }
        }
        job.invokeOnCompletion {
            firstFullState.completeExceptionally(RobotClosedException("robot ${device.name} closed before it reported a state"))
        }
    }

    private val mirror = SettingsMirror(link, options.settingsCache, debugLog)

    /** Where the link stands; says [ConnectionState.Lost] the moment a loss is noticed. */
    public val connection: StateFlow<ConnectionState> get() = link.connection

    /**
     * Every step of [connection], numbered, as it happens: a [StateFlow] keeps only the latest state, so a slow
     * collector of [connection] may miss a `Reconnecting(n)`. This flow keeps each step for every collector that is
     * no more than 256 steps behind; [ConnectionChange.number] counts them without gaps, so a gap says a collector
     * fell behind. Collect it before the steps you want to see happen (it replays nothing).
     */
    public val connectionChanges: SharedFlow<ConnectionChange> get() = link.changes

    /**
     * The whole robot state as last reported; `time.timeMs` is the robot time it was measured at. A reduced packet
     * updates encoders, wheel speeds, line position and time and keeps the rest. All zero until the first state
     * packet: [reportedState] waits for it.
     */
    public val state: StateFlow<RobotState> = _state.asStateFlow()

    /**
     * The whole state as the robot reported it: [state]'s value once a full state packet has arrived since the
     * connect, at once; before that, suspends until the first one arrives (right after [connect] returns it is
     * usually one sync period away). With [SyncMode.NONE] or [SyncMode.REDUCED] no full state comes: bound the wait
     * with a timeout. Throws [RobotClosedException] when the robot closes before its first state.
     *
     * ```
     * val volts = robot.reportedState().power.batteryMv / 1000.0
     * ```
     */
    public suspend fun reportedState(): RobotState {
        firstFullState.await()
        return _state.value
    }

    /**
     * Every state update, unconflated (a [StateFlow] drops values a slow collector did not see): its kind and the
     * resulting state. Buffers 256 updates, then drops the oldest.
     */
    public val stateUpdates: SharedFlow<StateUpdate> = _stateUpdates.asSharedFlow()

    /** Link counters: frames received, dropped (corrupt, truncated, oversized, unknown), retransmissions, reconnects. */
    public val linkStats: StateFlow<LinkStats> get() = link.linkStats

    /** Who the robot is, from its last `hello`. */
    public val identity: RobotIdentity get() = link.identity.value ?: error("robot not connected yet")

    /** Who drives the robot, as it last told this host: this host, another one (by its label), or none. */
    public val driving: StateFlow<Driving> get() = link.driving

    /**
     * What happened to the robot that its user should hear of: the drive changed hands ([RobotEvent.DriverChanged],
     * also when another host took it from this one), the robot restarted ([RobotEvent.Restarted]). Buffers 256 events
     * for each collector, then drops the oldest; replays nothing.
     */
    public val events: SharedFlow<RobotEvent> get() = link.events

    /**
     * Asks the robot for [role] (drive if free, watch, or take over) and suspends until it answered; returns who drives
     * then. The role counts for later reconnects too (a take-over as [Role.DRIVE]).
     */
    public suspend fun setRole(role: Role): Driving = link.requestRole(role)

    /** Takes the robot from the host that drives it (which is told); returns who drives then: this host. */
    public suspend fun takeOver(): Driving = setRole(Role.TAKE_OVER)

    /** State reflection: sync mode and period. */
    public val reflector: StateReflector = StateReflector(link, mirror)

    /** Typed tree of every setting, e.g. `robot.settings.linePid.kp.set(1.5)`. */
    public val settings: RobotSettings = RobotSettings(link, mirror)

    /** Movement queue (straight, rotate, arc), stop, and teleoperation. */
    public val locomotion: Locomotion = Locomotion(link, link.random) { mirror.values.value }

    /** The eight-spot line sensor. */
    public val lineSensor: LineSensor = LineSensor()

    /** Line following in the firmware. */
    public val lineFollower: LineFollower = LineFollower(link)

    /** IR proximity: encounters with other robots and obstacles, and IR messages. */
    public val proximity: Proximity = Proximity(link)

    /** The colour sensor under the robot. */
    public val colour: ColourSensor = ColourSensor()

    /** The accelerometer. */
    public val accelerometer: Accelerometer = Accelerometer()

    /** Battery, current and MCU temperature. */
    public val power: Power = Power()

    /** Wheel speeds and motor PWM. */
    public val motors: Motors = Motors()

    /** Dead-reckoned pose and wheel distances from the encoders (thesis 9.8). */
    public val odometry: Odometry = Odometry(link, settings)

    /** The track behaviour of thesis A.3, run by the robot's firmware: start, stop, reverse, speed, token. */
    public val track: TrackBehaviour = TrackBehaviour(link, settings)

    private val freshnessWatch = FreshnessWatch(link, reflector)

    /**
     * How current [state] is: live, or stale and why (the link is down, the sync mode does not carry the values, the
     * robot went quiet) and since when, for the values of full states ([StateFreshness.full]) and those reduced states
     * carry too ([StateFreshness.reduced]). It changes when that changes, not with every state. A face greys what is
     * not live and shows its age:
     *
     * ```
     * val f = robot.freshness.value.full
     * val battery = "%.2f V".format(robot.state.value.power.batteryMv / 1000.0) +
     *     if (f.isLive) "" else " (${f.age()?.inWholeSeconds} s ago)"
     * ```
     */
    public val freshness: StateFlow<StateFreshness> get() = freshnessWatch.freshness

    init {
        link.client = Client()
        freshnessWatch.start(link.connection)
    }

    /** What the link hands over, on its serial context: the path frame -> packet -> state -> flow ends here. */
    private inner class Client : LinkClient {
        override fun onPacket(packet: Packet) {
            when (packet) {
                is StateFull -> applyState(packet.state.toModel(), StateUpdate.Kind.FULL)
                is StateReduced -> applyState(_state.value.merge(packet), StateUpdate.Kind.REDUCED)
                is DebugText -> debugLog.robot(packet)
                is IrReceived -> proximity.received(packet)
                is MovementDone -> locomotion.reported(packet)
                is MovementLog -> locomotion.logArrived(packet)
                else -> {
                    link.noteUnexpected()
                    debugLog.host(1, "unexpected packet from the robot: $packet")
                }
            }
        }

        override suspend fun restore(hello: Hello, firstSession: Boolean, driver: Driver, exchange: suspend (Packet) -> Unit) {
            val seenMs = _state.value.time.timeMs
            val restarted = !firstSession && firstFullState.isCompleted && driver.timeMs < seenMs
            if (restarted) {
                debugLog.host(1, "${hello.name} restarted: its clock went back from ${seconds(seenMs)} to ${seconds(driver.timeMs)}")
                link.emit(RobotEvent.Restarted(seenMs, driver.timeMs))
            }
            mirror.align(hello, identity.address, exchange)
            if (!firstSession) locomotion.reconcile(exchange, resumed = hello.sessionResumed != 0, restarted = restarted)
            if (link.driving.value.byThisHost) reflector.restore(exchange) else reflector.adoptRobots()
        }

        override fun onFrameDropped() = locomotion.reportMayBeLost()

        override fun alreadyHeld(packet: Packet): Boolean = locomotion.robotHolds(packet)

        override val silenceTimeout: Duration?
            get() = if (reflector.mode.value == SyncMode.NONE) null else maxOf(options.silenceTimeout, reflector.period.value * 3)

        override val heartbeatPeriod: Duration
            get() = options.heartbeatPeriod ?: run {
                val failsafe = settings.link.failsafeTimeoutMs.value
                if (failsafe == 0) 1000.milliseconds else (failsafe / 3).coerceIn(30, 1000).milliseconds
            }
    }

    private fun applyState(state: RobotState, kind: StateUpdate.Kind) {
        _state.value = state
        freshnessWatch.heard(kind == StateUpdate.Kind.FULL, state.time.timeMs)
        lineSensor.update(state.line)
        motors.update(state.wheels)
        odometry.update(state.encoders, state.time.timeMs)
        locomotion.watch(state.encoders, state.time.timeMs, atRest = state.wheels.speedLeftMmps == 0 && state.wheels.speedRightMmps == 0)
        if (kind == StateUpdate.Kind.FULL) {
            firstFullState.complete(Unit)
            locomotion.update(state.locomotion, state.time.timeMs)
            lineFollower.update(state.lineFollow)
            proximity.update(state.proximity, state.time.timeMs)
            track.update(state.track)
            colour.update(state.colour)
            accelerometer.update(state.accel)
            power.update(state.power)
        }
        _stateUpdates.tryEmit(StateUpdate(kind, state))
    }

    /**
     * Says goodbye, closes the link and suspends until every coroutine the robot started has ended. The robot finishes
     * the movements this host queued (see [disconnect] with a [QueueOnLeave]). Commands still waiting fail with
     * [RobotClosedException]. Idempotent.
     */
    public suspend fun disconnect() {
        disconnect(QueueOnLeave.FINISH)
    }

    /**
     * Says goodbye (`goodbye`): the robot finishes or drops the movements this host queued, as [queue] says, stops
     * teleoperation, and no longer takes this host's link for a lost one (so its failsafe does not cut what it
     * finishes; it still stops what a host that vanishes without a goodbye drove). Then closes the link and suspends
     * until every coroutine the robot started has ended. Returns true when the robot acknowledged the goodbye; false
     * when the link was down or it did not answer (then its failsafe stops what this host drove). A watcher's goodbye
     * changes nothing on the robot. Idempotent: a robot closed already returns false.
     */
    public suspend fun disconnect(queue: QueueOnLeave): Boolean {
        val said = if (link.isClosing) false else link.leave(queue)
        link.close(null)
        withContext(kotlinx.coroutines.NonCancellable) { lifetime.join() }
        return said
    }

    /**
     * Closes the link and ends the robot's coroutines without waiting for them (for `use {}`); idempotent, safe to
     * call from any thread. A live link first carries a goodbye (the robot finishes this host's movements), sent
     * without waiting for the robot's answer: [disconnect] waits for it. The goodbye runs in the robot's scope, at
     * most [RobotOptions.commandTimeout]: the scope that made the robot completes only after it. Commands still
     * waiting fail with [RobotClosedException].
     */
    override fun close() {
        link.close(null, goodbye = true)
    }

    override fun toString(): String = "Robot(${link.identity.value?.name ?: device.name} at ${device.address}, ${connection.value})"
}

/**
 * One state update as it arrived.
 *
 * @property kind full or reduced packet.
 * @property state the resulting whole state; `state.time.timeMs` is the robot time of the update.
 */
public class StateUpdate internal constructor(public val kind: Kind, public val state: RobotState) {
    /** Robot time of this update, in milliseconds since the robot's reset. */
    public val timeMs: Long get() = state.time.timeMs

    /** Which state packet brought the update. */
    public enum class Kind { FULL, REDUCED }

    override fun toString(): String = "StateUpdate($kind at $timeMs ms)"
}

private fun seconds(ms: Long): String = "${ms / 1000}.${(ms % 1000) / 100} s"

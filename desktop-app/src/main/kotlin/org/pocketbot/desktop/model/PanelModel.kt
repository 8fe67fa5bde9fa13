package org.pocketbot.desktop.model

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.collect
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.flow.map
import kotlinx.coroutines.flow.onEach
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.sdk.HostLabel
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.ProtocolMismatchException
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.TrajectoryPoint
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.mqtt.BrokerRobotDevice
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.MergedDiscoverer
import org.pocketbot.sdk.transport.RobotDevice
import java.io.IOException
import kotlin.time.Duration.Companion.seconds

/** A robot some discoverer found, and which one. */
class FoundDevice(val device: RobotDevice, val source: String) {
    val address: String get() = device.address

    /** The gateway that serves the robot when it was found through a broker, else null. */
    val gateway: String? get() = (device as? BrokerRobotDevice)?.gateway

    /** Its name as every view shows it: GATEWAY/NAME for a robot behind a broker's gateway. */
    val name: String get() = gateway?.let { it + "/" + device.name } ?: device.name
}

/** The kinds of movement the form offers. */
enum class MovementKind(val title: String) { STRAIGHT("Straight"), ROTATE("Rotate"), ARC("Arc") }

/** The movement form as the user left it: the kind and the numbers as typed. */
data class MovementDraft(val kind: MovementKind = MovementKind.STRAIGHT, val amount: String = "0.10", val radius: String = "0.10", val speed: String = "0.20") {
    /** The movement these fields describe; [IllegalArgumentException] (or a [NumberFormatException]) says what is wrong. */
    fun movement(): Movement {
        val a = amount.trim().toDouble()
        val v = speed.trim().toDouble()
        return when (kind) {
            MovementKind.STRAIGHT -> Movement.Straight(a, v)
            MovementKind.ROTATE -> Movement.Rotate(a, v)
            MovementKind.ARC -> Movement.Arc(radius.trim().toDouble(), a, v)
        }
    }
}

/** Something the user should read: a failed connect, a refused setting, a file that did not parse. */
class Notice(val id: Long, val text: String, val isError: Boolean)

/**
 * The panel's root state holder: the robots every discoverer found, the connected ones, which one is selected, the
 * embedded emulator, and what went wrong lately. The composables only read its flows and call its functions; the SDK
 * work runs in [scope].
 */
class PanelModel(
    val scope: CoroutineScope,
    /** Where to look for robots besides the embedded emulator, by a name people understand. */
    private val sources: Map<String, Discoverer>,
    /** The embedded emulator, or null when the panel runs without one. */
    val emulator: EmulatorModel?,
    private val options: RobotOptions = RobotOptions { hostLabel = HostLabel.of("panel") },
) : AutoCloseable {
    private val _found = MutableStateFlow<List<FoundDevice>>(emptyList())
    private val _robots = MutableStateFlow<List<RobotModel>>(emptyList())
    private val _selected = MutableStateFlow<RobotModel?>(null)
    private val _notices = MutableStateFlow<List<Notice>>(emptyList())
    private val _scanning = MutableStateFlow(false)
    private val _connecting = MutableStateFlow<Set<String>>(emptySet())
    private val _problems = MutableStateFlow<Map<String, String>>(emptyMap())
    private val _connectFailures = MutableStateFlow<Map<String, String>>(emptyMap())
    private var noticeIds = 0L
    private var scanJob: Job? = null

    /** Every robot found by the last scans, one entry per address, by name as [robots]. */
    val found: StateFlow<List<FoundDevice>> = _found.asStateFlow()

    /** The connected robots by name (numbers in names by value: PocketBot-2 before PocketBot-10), then id and address. */
    val robots: StateFlow<List<RobotModel>> = _robots.asStateFlow()

    /** The robot the detail views show. */
    val selected: StateFlow<RobotModel?> = _selected.asStateFlow()

    /** Messages for the user, newest last. */
    val notices: StateFlow<List<Notice>> = _notices.asStateFlow()

    /** True while a scan runs. */
    val scanning: StateFlow<Boolean> = _scanning.asStateFlow()

    /** Sources that could not search in the last scan (no Bluetooth adapter, no emulator on the control port), and why. */
    val problems: StateFlow<Map<String, String>> = _problems.asStateFlow()

    /** Addresses being connected now. */
    val connecting: StateFlow<Set<String>> = _connecting.asStateFlow()

    /**
     * Why the last connect of a found robot failed, by address, shown beside the robot where the user clicked: a
     * firmware that speaks another protocol says so and what to do, not just "cannot connect".
     */
    val connectFailures: StateFlow<Map<String, String>> = _connectFailures.asStateFlow()

    /**
     * What the user typed into the movement form: it outlives the view (another tab, another robot) and the robots
     * (a reconnect, a world restarted), so it is kept here, not in the composable.
     */
    val movementDraft = MutableStateFlow(MovementDraft())

    /** Looks for robots with every source at once; each shows up as soon as its source finds it. */
    fun scan() {
        if (scanJob?.isActive == true) return
        val all = buildMap {
            emulator?.let { put(EMBEDDED, it.discoverer) }
            putAll(sources)
        }
        // Each source tags what it finds, so the list can say where a robot was found.
        val tagged = all.mapValues { (name, source) ->
            object : Discoverer {
                override fun discover() = source.discover().map { FoundDevice(it, name) }.onEach(::add).map { it.device }
            }
        }
        _problems.value = emptyMap()
        _scanning.value = true
        scanJob = scope.launch {
            try {
                MergedDiscoverer(tagged) { source, e -> _problems.update { it + (source to (e.message ?: e.toString())) } }
                    .discover().collect()
            } finally {
                _scanning.value = false
            }
        }
    }

    private fun add(d: FoundDevice) = _found.update { list -> (list.filterNot { it.address == d.address } + d).sortedWith(foundByName) }

    /** Connects [devices] at once; each robot joins [robots] when its handshake is done. */
    fun connect(devices: List<FoundDevice>) {
        for (d in devices) {
            if (d.address in _connecting.value || _robots.value.any { it.address == d.address }) continue
            _connecting.update { it + d.address }
            _connectFailures.update { it - d.address }
            scope.launch {
                try {
                    val robot = d.device.connect(scope, options)
                    val emulated = emulator?.handleFor(robot.identity.address)
                    // The world view draws the odometry pose over the robot: it starts where the robot is, not at (0, 0).
                    emulated?.let { robot.odometry.reset(it.truePose) }
                    val model = RobotModel(robot, scope, emulated, ::notify, gateway = d.gateway)
                    _robots.update { (it + model).sortedWith(byName) }
                    if (_selected.value == null) _selected.value = model
                } catch (e: CancellationException) {
                    throw e
                } catch (e: Exception) {
                    val why = when (e) {
                        is ProtocolMismatchException -> "firmware mismatch: ${e.message}. Update the robot's firmware or this " +
                            "panel, so that both are built from the same protocol/pocketbot.toml."
                        else -> "cannot connect: ${e.message ?: e}"
                    }
                    _connectFailures.update { it + (d.address to why) }
                    notify("${d.name}: $why")
                } finally {
                    _connecting.update { it - d.address }
                }
            }
        }
    }

    /** Disconnects [robot]: its link closes, and it leaves [robots]. */
    fun disconnect(robot: RobotModel) {
        _robots.update { it - robot }
        if (_selected.value == robot) _selected.value = _robots.value.firstOrNull()
        scope.launch { robot.close() }
    }

    fun select(robot: RobotModel) { _selected.value = robot }

    /**
     * Gives [command] to every connected robot at once, for what a fleet does together (the track behaviour); each
     * robot reports its own failure, and the others go on.
     */
    fun everyRobot(command: (RobotModel) -> Unit) = _robots.value.forEach(command)

    /** Finds the embedded emulator's robots and connects every one of them; returns them once connected. */
    suspend fun connectEmbedded(): List<RobotModel> {
        val emu = emulator ?: return emptyList()
        val devices = emu.discoverer.discover().toList().map { FoundDevice(it, EMBEDDED) }
        devices.forEach(::add)
        connect(devices)
        val addresses = devices.map { it.address }.toSet()
        _connecting.first { busy -> addresses.none { it in busy } }
        return _robots.value.filter { it.address in addresses }
    }

    /**
     * Restarts the embedded emulator with [world] (a shipped name or a world file) and [count] robots, and connects
     * them. A world that does not load, or a count out of range, is reported and the running emulator stays as it is.
     */
    fun restartEmulator(world: String, count: Int) {
        val emu = emulator ?: return
        scope.launch {
            val spec = try {
                require(count in 1..EmulatorModel.MAX_ROBOTS) { "robots must be 1..${EmulatorModel.MAX_ROBOTS}, not $count" }
                emu.load(world)
            } catch (e: IllegalArgumentException) {
                return@launch notify("cannot start world $world: ${e.message}")
            }
            val old = _robots.value.filter { it.emulated != null }
            _robots.update { it - old.toSet() }
            if (_selected.value in old) _selected.value = null
            for (r in old) r.close()
            _found.update { list -> list.filterNot { it.source == EMBEDDED } }
            try {
                emu.restart(spec, count)
            } catch (e: IOException) {
                notify("the new world runs, but not on the network: ${e.message}")
            }
            connectEmbedded()
        }
    }

    /**
     * Serves the embedded emulator's robots on the network (see [EmulatorModel.serve]), so a phone or another computer
     * drives them while the panel draws them; a place it cannot listen at is reported.
     */
    fun serveEmulator() {
        val emu = emulator ?: return
        try {
            emu.serve()
        } catch (e: IOException) {
            val at = "${ListenAddress.hostText(emu.serveAt.address)}:${emu.serveAt.port}"
            notify("cannot serve the emulator on the network at $at: ${e.message}")
        }
    }

    /** Takes the embedded emulator's robots off the network again. */
    fun stopServingEmulator() {
        emulator?.stopServing()
    }

    /**
     * [robot]'s path as CSV, one point per line: its odometry (`path` = `odometry`) and, for a robot of the embedded
     * emulator, the path it really took (`true`), for comparing the two in a spreadsheet or a script.
     */
    fun trajectoryCsv(robot: RobotModel): String = buildString {
        append("path,time_ms,x_m,y_m,heading_rad\n")
        fun add(path: String, points: List<TrajectoryPoint>) {
            for (p in points) append(path).append(',').append(p.timeMs).append(',').append(p.pose.xM).append(',')
                .append(p.pose.yM).append(',').append(p.pose.headingRad).append('\n')
        }
        add("odometry", robot.robot.odometry.trajectory.points.value)
        emulator?.truePath(robot.address)?.let { add("true", it.points.value) }
    }

    /** Adds a message for the user. */
    fun notify(text: String, isError: Boolean = true) {
        _notices.update { (it + Notice(++noticeIds, text, isError)).takeLast(MAX_NOTICES) }
    }

    fun dismiss(notice: Notice) = _notices.update { it - notice }

    /** Disconnects every robot (each link closed, within a few seconds) and stops the emulator. */
    override fun close() {
        scanJob?.cancel()
        runBlocking { withTimeoutOrNull(3.seconds) { for (r in _robots.value) r.close() } }
        _robots.value = emptyList()
        emulator?.close()
    }

    private companion object {
        const val MAX_NOTICES = 5
        const val EMBEDDED = "embedded emulator"

        /** Every view lists robots in this one order, whatever order they connected in. */
        val byName: Comparator<RobotModel> = Comparator<RobotModel> { a, b -> compareNatural(a.name, b.name) }
            .thenBy { it.robot.identity.robotId }.thenBy { it.address }
        val foundByName: Comparator<FoundDevice> = Comparator<FoundDevice> { a, b -> compareNatural(a.name, b.name) }
            .thenBy { it.address }
    }
}

/** Compares [a] and [b] as people sort names: runs of digits by their value, the rest by character ("PocketBot-2" < "PocketBot-10"). */
fun compareNatural(a: String, b: String): Int {
    var i = 0
    var j = 0
    while (i < a.length && j < b.length) {
        if (a[i].isDigit() && b[j].isDigit()) {
            val ei = (i until a.length).firstOrNull { !a[it].isDigit() } ?: a.length
            val ej = (j until b.length).firstOrNull { !b[it].isDigit() } ?: b.length
            val na = a.substring(i, ei).trimStart('0')
            val nb = b.substring(j, ej).trimStart('0')
            val c = if (na.length != nb.length) na.length - nb.length else na.compareTo(nb)
            if (c != 0) return c
            i = ei; j = ej
        } else {
            val c = a[i].compareTo(b[j])
            if (c != 0) return c
            i++; j++
        }
    }
    return (a.length - i) - (b.length - j)
}

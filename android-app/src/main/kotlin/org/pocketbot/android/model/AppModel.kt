package org.pocketbot.android.model

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.map
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import org.pocketbot.sdk.ProtocolMismatchException
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.MergedDiscoverer
import org.pocketbot.sdk.transport.RobotDevice

/** Where the phone's Bluetooth stands, for the app to say what is missing and offer the way on. */
enum class BluetoothStatus {
    /** Permissions granted and the adapter on: robots can be found and connected. */
    READY,

    /** The permissions have not been asked for yet (or not answered). */
    PERMISSION_NEEDED,

    /** The user refused them; Android still shows its dialog if asked again. */
    PERMISSION_REFUSED,

    /** Refused for good ("Don't allow" twice): Android shows no dialog any more, only the app's settings can allow them. */
    PERMISSION_BLOCKED,

    /** Bluetooth is switched off. */
    OFF,

    /** This device has no Bluetooth. */
    UNAVAILABLE,
}

/** The phone's Bluetooth: its status, and while it is [BluetoothStatus.READY] a discoverer and devices by address. */
interface BluetoothPort {
    val status: StateFlow<BluetoothStatus>

    /** Finds PocketBots, or with [everyDevice] every device nearby (a robot renamed, a module never renamed). */
    fun discoverer(everyDevice: Boolean): Discoverer?

    /** The device at [address] (`00:11:22:33:44:55`), or null when that is no Bluetooth address. */
    fun deviceAt(address: String): RobotDevice?
    fun refresh()
}

/** The app's screens, in the order of the navigation bar. */
enum class Screen(val title: String) {
    ROBOTS("Robots"), SENSOR("Sensor"), CALIBRATE("Calibrate"), DRIVE("Drive"), FOLLOW("Follow"), PATH("Path")
}

/** A robot a search found: where, and through what. */
class FoundRobot(val device: RobotDevice, val source: String) {
    val name: String get() = device.name
    val address: String get() = device.address
}

/** Something the user should know: a failure, a warning, or news. */
class Notice(val text: String, val kind: Kind) {
    enum class Kind { INFO, WARNING, ERROR }

    override fun toString(): String = "$kind: $text"
}

/**
 * The app's state, alive as long as the process (it belongs to the Application, not to an Activity): the screen
 * shown, the robots found, the connected robot's [RobotSession], and what the user should be told. Rotating the phone
 * or sending the app to the background recreates the Activity, which reads this again; the connection stays.
 *
 * [scope] runs everything here and the robots' work unless its context names a
 * [org.pocketbot.sdk.RobotRuntime]; it is the main thread on a phone. Every method is called on that thread.
 *
 * @param bluetooth the phone's Bluetooth.
 * @param sources other places to find robots, by a name people understand (tests: an in-process emulator).
 * @param emulatorAt how to ask an emulator on the network for its robots, from host and control port.
 */
class AppModel(
    val scope: CoroutineScope,
    val bluetooth: BluetoothPort,
    private val sources: Map<String, Discoverer> = emptyMap(),
    private val emulatorAt: (host: String, port: Int) -> Discoverer,
) {
    private val _screen = MutableStateFlow(Screen.ROBOTS)
    private val _found = MutableStateFlow<List<FoundRobot>>(emptyList())
    private val _scanning = MutableStateFlow(false)
    private val _connecting = MutableStateFlow<String?>(null)
    private val _session = MutableStateFlow<RobotSession?>(null)
    private val _notice = MutableStateFlow<Notice?>(null)
    private var scan: Job? = null

    init {
        // Switching Bluetooth off breaks a Bluetooth robot's link at once; whichever Android reports first, the broken
        // socket or the switch, the user reads why and how it comes back.
        scope.launch {
            bluetooth.status.collect { status ->
                if (status == BluetoothStatus.OFF) _session.value?.whyLost()?.let { tell(it, Notice.Kind.ERROR) }
            }
        }
    }

    val screen: StateFlow<Screen> = _screen.asStateFlow()
    val found: StateFlow<List<FoundRobot>> = _found.asStateFlow()
    val scanning: StateFlow<Boolean> = _scanning.asStateFlow()

    /** The name of the robot being connected, or null. */
    val connecting: StateFlow<String?> = _connecting.asStateFlow()

    /** The connected robot, or null. */
    val session: StateFlow<RobotSession?> = _session.asStateFlow()

    /** The latest thing to tell the user, until [dismissNotice] or a newer one. */
    val notice: StateFlow<Notice?> = _notice.asStateFlow()

    /** The emulator address the user typed last (`host:port` of its control port). */
    val emulatorAddress: MutableStateFlow<String> = MutableStateFlow(DEFAULT_EMULATOR_ADDRESS)

    /** Whether the app asked for the notification permission in this process (Android 13 on): it asks once. */
    var askedForNotifications: Boolean = false

    /** The Bluetooth address the user typed last. */
    val bluetoothAddress: MutableStateFlow<String> = MutableStateFlow("")

    private val _everyDevice = MutableStateFlow(false)

    /** Whether a Bluetooth search lists every device, not only those named PocketBot. */
    val everyDevice: StateFlow<Boolean> = _everyDevice.asStateFlow()

    /** Lists every Bluetooth device or only PocketBots, and searches again. */
    fun showEveryDevice(on: Boolean) {
        if (_everyDevice.value == on) return
        _everyDevice.value = on
        if (!on) _found.update { list -> list.filter { it.source != BLUETOOTH || it.device.looksLikePocketBot() } }
        if (bluetooth.status.value == BluetoothStatus.READY) scan()
    }

    /** Connects the Bluetooth device at the address the user typed (a robot that cannot be found by name). */
    fun connectBluetoothAddress(text: String) {
        bluetoothAddress.value = text.trim()
        if (bluetooth.status.value != BluetoothStatus.READY) return tell("Bluetooth is not ready: allow it and turn it on first", Notice.Kind.WARNING)
        val device = bluetooth.deviceAt(text.trim().uppercase())
            ?: return tell("\"$text\" is no Bluetooth address: write six pairs of hex digits, e.g. 00:11:22:33:44:55", Notice.Kind.ERROR)
        connect(FoundRobot(device, BLUETOOTH))
    }

    fun show(screen: Screen) {
        if (_screen.value == Screen.DRIVE && screen != Screen.DRIVE) _session.value?.joystick?.release()
        _screen.value = screen
    }

    fun tell(text: String, kind: Notice.Kind = Notice.Kind.INFO) {
        _notice.value = Notice(text, kind)
    }

    fun dismissNotice() {
        _notice.value = null
    }

    /** Looks for robots over Bluetooth (when it is ready) and in [sources]; the list fills as they are found. */
    fun scan() {
        val all = LinkedHashMap(sources)
        bluetooth.discoverer(_everyDevice.value)?.let { all[BLUETOOTH] = it }
        search(all)
    }

    /** Asks the emulator whose control port is at [address] (`host:port`, the port 40000 when left out) for its robots. */
    fun findEmulator(address: String) {
        emulatorAddress.value = address.trim()
        val (host, port) = parseHostPort(address.trim()) ?: return tell("\"$address\" is no address: write host:port, e.g. 192.168.1.20:40000", Notice.Kind.ERROR)
        search(mapOf("emulator at $host:$port" to emulatorAt(host, port)))
    }

    private fun search(discoverers: Map<String, Discoverer>) {
        if (discoverers.isEmpty()) return tell("Nothing to search: Bluetooth is not ready and no emulator address is given", Notice.Kind.WARNING)
        scan?.cancel()
        _scanning.value = true
        scan = scope.launch {
            try {
                // All sources at once; one that fails (Bluetooth refused, no emulator there) is told and the others go on.
                val named = discoverers.mapValues { (name, d) ->
                    object : Discoverer {
                        override fun discover() = d.discover().map { Found(it, name) }
                    }
                }
                MergedDiscoverer(named) { name, e -> tell("$name: ${e.message ?: e}", Notice.Kind.ERROR) }.discover().collect { found ->
                    found as Found
                    add(FoundRobot(found.device, found.source))
                }
            } finally {
                _scanning.value = false
            }
        }
    }

    /** A device as a search source found it, with the source's name. */
    private class Found(val device: RobotDevice, val source: String) : RobotDevice by device

    /** A new robot goes last; one found again (a name resolved later) keeps its place. */
    private fun add(robot: FoundRobot) {
        _found.update { list ->
            val at = list.indexOfFirst { it.address == robot.address }
            if (at < 0) list + robot else list.toMutableList().also { it[at] = robot }
        }
    }

    /** Connects [robot], closing the robot connected before (one robot at a time). */
    fun connect(robot: FoundRobot) {
        if (_connecting.value != null) return
        _connecting.value = robot.name
        scan?.cancel()
        scope.launch {
            try {
                _session.value?.close()
                _session.value = null
                val connected = robot.device.connect(scope)
                val overBluetooth = robot.source == BLUETOOTH
                _session.value = RobotSession(connected, scope, ::tell) {
                    if (overBluetooth && bluetooth.status.value == BluetoothStatus.OFF) bluetoothOff(connected.identity.name) else null
                }
                val link = _session.value?.linkKind?.value
                if (link?.warning == true) tell("Connected to ${connected.identity.name} over ${link.text}.", Notice.Kind.WARNING) else dismissNotice()
                _screen.value = Screen.SENSOR
            } catch (e: CancellationException) {
                throw e
            } catch (e: ProtocolMismatchException) {
                tell("${robot.name} runs other firmware: ${e.message}. Update the robot or the app.", Notice.Kind.ERROR)
            } catch (e: Exception) {
                tell("Cannot connect ${robot.name}: ${failure(e)}", Notice.Kind.ERROR)
            } finally {
                _connecting.value = null
            }
        }
    }

    /** Stops the robot and closes its connection. */
    fun disconnect() {
        val session = _session.value ?: return
        _session.value = null
        _screen.value = Screen.ROBOTS
        scope.launch { session.close() }
    }

    /** The app is closing: the robot stops, the connection closes. */
    fun closeApp() {
        scan?.cancel()
        disconnect()
    }

    private fun bluetoothOff(robot: String) =
        "Bluetooth is off, so the link to $robot is lost: the robot stops on its own within a second. Turn Bluetooth on and the app reconnects."

    companion object {
        /** The source name of robots found over Bluetooth. */
        const val BLUETOOTH: String = "Bluetooth"

        /** The name every PocketBot2 advertises starts with this (`PocketBot-3`). */
        const val NAME_PREFIX: String = "PocketBot"

        /** True for a device whose name is a PocketBot's. */
        fun RobotDevice.looksLikePocketBot(): Boolean = name.startsWith(NAME_PREFIX, ignoreCase = true)

        /** The control port of an emulator on the computer an Android emulator (AVD) runs on. */
        const val DEFAULT_EMULATOR_ADDRESS: String = "10.0.2.2:40000"
        private const val DEFAULT_CONTROL_PORT = 40000

        /** `host:port`, `host` (port 40000) or `[v6]:port` into host and port; null when it is none. */
        fun parseHostPort(text: String): Pair<String, Int>? {
            if (text.isEmpty() || text.any { it.isWhitespace() }) return null
            val bracketed = Regex("""\[([0-9a-fA-F:.]+)](?::(\d+))?""").matchEntire(text)
            val (host, portText) = when {
                bracketed != null -> bracketed.groupValues[1] to bracketed.groupValues[2].ifEmpty { null }
                text.count { it == ':' } == 1 -> text.substringBefore(':') to text.substringAfter(':')
                text.count { it == ':' } == 0 -> text to null
                else -> return null
            }
            if (host.isEmpty()) return null
            val port = portText?.toIntOrNull() ?: if (portText == null) DEFAULT_CONTROL_PORT else return null
            return if (port in 1..65535) host to port else null
        }
    }
}

package org.pocketbot.desktop.model

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.isActive
import kotlinx.coroutines.launch
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.sdk.ColourMode
import org.pocketbot.sdk.CommandTimeoutException
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.DebugMessage
import org.pocketbot.sdk.Driving
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementHandle
import org.pocketbot.sdk.MovementResult
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotClosedException
import org.pocketbot.sdk.RobotEvent
import org.pocketbot.sdk.RobotException
import org.pocketbot.sdk.SettingField
import org.pocketbot.sdk.SettingRefusedException
import org.pocketbot.sdk.StateFreshness
import java.io.File
import kotlin.time.TimeMark
import kotlin.time.TimeSource

/**
 * Where a setting's edit stands: written and waiting, confirmed by the robot, refused by it (or not a value at all),
 * or never answered because the link failed first: then the robot may or may not hold it.
 */
sealed class EditStatus {
    data class Pending(val text: String) : EditStatus()
    data class Acknowledged(val text: String) : EditStatus()
    data class Refused(val reason: String) : EditStatus()
    data class NotConfirmed(val reason: String) : EditStatus()
}

/**
 * One line of the console: a message, or the same message repeated [count] times in a row (the SDK's reconnect
 * attempts while a robot is away, say), shown once with its count instead of once per repeat.
 */
class ConsoleLine(val message: DebugMessage, val count: Int = 1, val since: TimeMark = TimeSource.Monotonic.markNow()) {
    /** The message as shown: the latest text, and how often it came since when. */
    fun text(): String = message.toString() + if (count > 1) " · $count times in ${since.elapsedNow().inWholeSeconds} s" else ""

    /** True when [m] says the same as this line's message but for its numbers (attempt 7, attempt 8, ...). */
    fun repeatedBy(m: DebugMessage): Boolean =
        m.source == message.source && m.module == message.module && m.level == message.level && shape(m.text) == shape(message.text)

    private fun shape(text: String) = text.replace(DIGITS, "#")

    private companion object {
        val DIGITS = Regex("""\d+""")
    }
}

/** A robot's link that is down: since when, how many attempts to reconnect failed meanwhile, and the latest reason. */
class LinkTrouble(val since: TimeMark, val attempts: Int, val reason: String)

/**
 * A movement this panel queued, and how it ended once it did ([result]). A new value when it ends, so that a view of
 * [RobotModel.movements] sees the change.
 */
class QueuedMovement(val handle: MovementHandle, val result: MovementResult? = null) {
    val text: String get() = handle.movement.toString()
}

/**
 * One connected robot as the panel drives it: commands, settings edits with their status, the console, teleoperation
 * and tuning. Everything it does goes through the SDK's public API; failures become messages ([notify]), never
 * crashes. Another host may drive the robot ([driving]): the panel then watches it until the user takes it over
 * ([takeOver]), and says so when the robot is taken from it, given back, or restarts.
 */
class RobotModel(
    val robot: Robot,
    private val scope: CoroutineScope,
    /** The emulated robot behind it, for the true pose; null for a real robot. */
    val emulated: RobotHandle?,
    private val notify: (String, Boolean) -> Unit,
    /** The gateway that serves the robot when it is reached through a broker, else null. */
    val gateway: String? = null,
) {
    /** The robot's name as every view shows it: GATEWAY/NAME behind a broker's gateway (two hosts' PocketBot-1 differ). */
    val name: String = gateway?.let { it + "/" + robot.identity.name } ?: robot.identity.name
    val address: String = robot.identity.address

    private val _movements = MutableStateFlow<List<QueuedMovement>>(emptyList())
    private val _edits = MutableStateFlow<Map<String, EditStatus>>(emptyMap())
    private val _console = MutableStateFlow<List<ConsoleLine>>(emptyList())
    private var teleop: Job? = null
    @Volatile private var wheelTarget = 0.0 to 0.0

    /** The movements queued from this panel, newest last (the last [MAX_MOVEMENTS]), running or ended. */
    val movements: StateFlow<List<QueuedMovement>> = _movements.asStateFlow()

    /** The status of every setting edited in this panel, by name. */
    val edits: StateFlow<Map<String, EditStatus>> = _edits.asStateFlow()

    private val _reloads = MutableStateFlow(0)
    /** Counts reads of the whole settings struct (read all, defaults, import): edit fields start over from the robot's values. */
    val reloads: StateFlow<Int> = _reloads.asStateFlow()

    /** The robot's debug text and the SDK's link messages, the last [MAX_CONSOLE] lines, a repeated message as one. */
    val console: StateFlow<List<ConsoleLine>> = _console.asStateFlow()

    /** PID tuning of this robot. */
    val tuning = TuningModel(robot, scope) { notify(it, true) }

    /** Which values of [Robot.state] are live, and since when the others are not: views grey those, with their age. */
    val freshness: StateFlow<StateFreshness> get() = robot.freshness

    private val _linkTrouble = MutableStateFlow<LinkTrouble?>(null)
    /** The link while it is down (since when, failed attempts, why), or null while it is up. */
    val linkTrouble: StateFlow<LinkTrouble?> = _linkTrouble.asStateFlow()

    /** Who drives the robot: this panel, another host (by its label), or none. */
    val driving: StateFlow<Driving> get() = robot.driving

    private val jobs = listOf(
        scope.launch { robot.debugLog.messages.collect(::log) },
        scope.launch { robot.connection.collect(::followLink) },
        scope.launch { robot.events.collect(::tell) },
    )

    private fun log(m: DebugMessage) = _console.update { lines ->
        val last = lines.lastOrNull()
        if (last != null && last.repeatedBy(m)) lines.dropLast(1) + ConsoleLine(m, last.count + 1, last.since)
        else (lines + ConsoleLine(m)).takeLast(MAX_CONSOLE)
    }

    private fun followLink(c: ConnectionState) = _linkTrouble.update { t ->
        when (c) {
            ConnectionState.Connected, ConnectionState.Connecting -> null
            is ConnectionState.Lost -> LinkTrouble(t?.since ?: TimeSource.Monotonic.markNow(), t?.attempts ?: 0, c.reason)
            is ConnectionState.Reconnecting -> LinkTrouble(t?.since ?: TimeSource.Monotonic.markNow(), c.attempt - 1, t?.reason ?: "reconnecting")
            is ConnectionState.Closed -> LinkTrouble(t?.since ?: TimeSource.Monotonic.markNow(), t?.attempts ?: 0, c.cause?.message ?: "closed")
        }
    }

    /** Takes the robot from the host that drives it (which is told); the panel drives it from then on. */
    fun takeOver() = act("take over") { robot.takeOver() }

    private fun tell(event: RobotEvent) = when (event) {
        is RobotEvent.DriverChanged -> when {
            event.taken -> notify("$name was taken over by ${event.driving.driver ?: "another host"}: this panel only watches it now (Take over to drive it again)", true)
            event.driving.byThisHost -> notify("this panel drives $name", false)
            else -> {}
        }
        is RobotEvent.Restarted -> notify("$name restarted: its clock went back from ${seconds(event.lastSeenTimeMs)} to ${seconds(event.timeMs)}; " +
            "what it had queued is gone", true)
    }

    private fun seconds(ms: Long) = "%.1f s".format(ms / 1000.0)

    /** Queues [movement]; it shows in [movements] at once and gets its result when it ends. */
    fun enqueue(movement: Movement) = act("enqueue $movement") {
        val handle = robot.locomotion.enqueue(movement)
        _movements.update { (it + QueuedMovement(handle)).takeLast(MAX_MOVEMENTS) }
        val result = handle.await()
        _movements.update { list -> list.map { if (it.handle === handle) QueuedMovement(handle, result) else it } }
    }

    /** Stops the robot: braking along the profile, or [immediate]ly. Also ends teleoperation. */
    fun stop(immediate: Boolean) {
        teleop?.cancel()
        teleop = null
        wheelTarget = 0.0 to 0.0
        act("stop") { robot.locomotion.stop(immediate) }
    }

    /**
     * Teleoperation: the robot holds these wheel speeds. The panel sends them again a few times a second while they
     * are not zero, so the robot's link failsafe does not stop it while a key is held or the joystick is deflected.
     */
    fun drive(leftMps: Double, rightMps: Double) {
        wheelTarget = leftMps to rightMps
        if (teleop?.isActive == true) return
        teleop = scope.launch {
            var last: Pair<Double, Double>? = null
            while (isActive) {
                val target = wheelTarget
                if (target != last || target != (0.0 to 0.0)) robot.locomotion.setWheelSpeeds(target.first, target.second)
                if (target == (0.0 to 0.0) && last == target) break
                last = target
                delay(TELEOP_PERIOD_MS)
            }
        }
    }

    fun startLineFollowing(speedMps: Double?, colourMode: ColourMode) =
        act("start line following") { robot.lineFollower.start(speedMps, colourMode) }

    fun stopLineFollowing() = act("stop line following") { robot.lineFollower.stop() }

    fun startTrack() = act("start the track behaviour") { robot.track.start() }
    fun stopTrack() = act("stop the track behaviour") { robot.track.stop() }
    fun reverseTrack() = act("reverse the track behaviour") { robot.track.reverse() }

    /**
     * Sets the track behaviour's cruise speed (m/s) from the [text] a person typed, with the SDK's
     * [org.pocketbot.sdk.TrackBehaviour.setSpeed]; its status shows in [edits] under [TRACK_SPEED], as a setting's does.
     */
    fun setTrackSpeed(text: String) {
        val mps = text.trim().toDoubleOrNull()
            ?: return _edits.update { it + (TRACK_SPEED to EditStatus.Refused("not a number: $text")) }
        confirm(TRACK_SPEED, text) {
            robot.track.setSpeed(mps)
            robot.settings.track.speedMps.valueText
        }
    }

    /**
     * Writes the setting [name] from the [text] a person typed: that field only. [edits] shows it pending, then
     * acknowledged (the robot's value reads back) or refused with the robot's reason; a text that is no value of the
     * field is refused here and nothing is sent.
     */
    fun write(name: String, text: String) {
        val field = robot.settings[name] ?: return notify("no setting $name", true)
        val value = try { field.parse(text) } catch (e: IllegalArgumentException) {
            _edits.update { it + (name to EditStatus.Refused(e.message ?: "not a value")) }
            return
        }
        confirm(name, text) {
            @Suppress("UNCHECKED_CAST")
            (field as SettingField<Any>).set(value!!)
            field.valueText
        }
    }

    /** Shows the edit of [name] pending while [write] runs, then what it returned (the robot's value) or why it failed. */
    private fun confirm(name: String, text: String, write: suspend () -> String) {
        _edits.update { it + (name to EditStatus.Pending(text)) }
        scope.launch {
            val status = try {
                EditStatus.Acknowledged(write())
            } catch (e: SettingRefusedException) {
                EditStatus.Refused(e.message ?: "refused")
            } catch (e: CancellationException) {
                throw e
            } catch (e: RobotClosedException) {
                EditStatus.NotConfirmed("the link closed before the robot answered")
            } catch (e: CommandTimeoutException) {
                EditStatus.NotConfirmed("no answer from the robot (${e.message}); Read all shows what it holds")
            } catch (e: Exception) {
                EditStatus.NotConfirmed("the link failed: ${e.message ?: e}")
            }
            _edits.update { it + (name to status) }
        }
    }

    fun readAllSettings() = act("read settings") { robot.settings.readAll(); reloaded() }
    fun saveSettings() = act("save settings") { robot.settings.save(); notify("$name: settings saved to EEPROM", false) }
    fun loadDefaults() = act("load defaults") { robot.settings.loadDefaults(); reloaded() }

    private fun reloaded() {
        _edits.value = emptyMap()
        _reloads.update { it + 1 }
    }

    /** Writes every setting as JSON to [file]. */
    fun exportSettings(file: File) = act("export settings") {
        file.writeText(robot.settings.exportJson())
        notify("$name: settings exported to ${file.name}", false)
    }

    /**
     * Reads settings from the JSON [file] and writes them to the robot, all or nothing: the SDK checks the whole file
     * before it writes anything, and when the robot refuses one of its values the ones written before it are put back.
     */
    fun importSettings(file: File) = act("import ${file.name}") {
        val text = file.readText()
        val before = robot.settings.exportJson()
        try {
            robot.settings.importJson(text)
        } catch (e: SettingRefusedException) {
            robot.settings.importJson(before)
            throw RobotException("${e.message}; nothing of ${file.name} was kept", e)
        } finally {
            reloaded()
        }
        notify("$name: settings imported from ${file.name}", false)
    }

    /** Sets the robot's debug verbosity (1 errors .. 4 trace). */
    fun setDebugLevel(level: Int) = write("debug.level", level.toString())

    fun clearConsole() { _console.value = emptyList() }

    private fun act(what: String, block: suspend () -> Unit) {
        scope.launch {
            try {
                block()
            } catch (e: CancellationException) {
                throw e
            } catch (e: RobotException) {
                notify("$name: $what: ${e.message}", true)
            } catch (e: Exception) {
                notify("$name: $what failed: ${e.message ?: e}", true)
            }
        }
    }

    /** Closes the link to the robot. */
    suspend fun close() {
        teleop?.cancel()
        jobs.forEach { it.cancel() }
        tuning.stop()
        robot.disconnect()
    }

    override fun toString(): String = "$name ($address)"

    companion object {
        const val MAX_MOVEMENTS = 50
        const val MAX_CONSOLE = 500
        /** Well inside the robot's default failsafe (1000 ms). */
        const val TELEOP_PERIOD_MS = 200L
        /** The setting the track behaviour's speed field writes, as [edits] names it. */
        const val TRACK_SPEED = "track.speed_mps"
    }
}

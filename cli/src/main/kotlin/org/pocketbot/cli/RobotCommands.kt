package org.pocketbot.cli

import com.github.ajalt.clikt.core.Context
import com.github.ajalt.clikt.core.NoSuchOption
import com.github.ajalt.clikt.core.CoreCliktCommand
import com.github.ajalt.clikt.core.ProgramResult
import com.github.ajalt.clikt.core.UsageError
import com.github.ajalt.clikt.core.requireObject
import com.github.ajalt.clikt.core.subcommands
import com.github.ajalt.clikt.parameters.arguments.argument
import com.github.ajalt.clikt.parameters.arguments.multiple
import com.github.ajalt.clikt.parameters.groups.provideDelegate
import com.github.ajalt.clikt.parameters.options.default
import com.github.ajalt.clikt.parameters.options.flag
import com.github.ajalt.clikt.parameters.options.option
import com.github.ajalt.clikt.parameters.options.split
import com.github.ajalt.clikt.parameters.types.choice
import com.github.ajalt.clikt.parameters.types.double
import com.github.ajalt.clikt.parameters.types.int
import com.github.ajalt.clikt.parameters.types.restrictTo
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.async
import kotlinx.coroutines.awaitAll
import kotlinx.coroutines.flow.channelFlow
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import kotlinx.coroutines.withTimeoutOrNull
import kotlinx.coroutines.CancellationException
import org.pocketbot.sdk.ColourMode
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.DebugModule
import org.pocketbot.sdk.DebugSource
import org.pocketbot.sdk.LocoMode
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementHandle
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.MovementResult
import org.pocketbot.sdk.QueueOnLeave
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotState
import org.pocketbot.sdk.Role
import org.pocketbot.sdk.SettingField
import org.pocketbot.sdk.SyncMode
import org.pocketbot.sdk.WheelDistances
import org.pocketbot.sdk.mqtt.BrokerException
import org.pocketbot.sdk.mqtt.connectBroker
import java.io.File
import kotlin.time.Duration.Companion.milliseconds

/**
 * A command on one or more robots: `ROBOT ARGS...`, or `--all ARGS...` for every robot found. [extra] is how many
 * arguments may follow the robot. It watches the robots ([role]): it reads, and never disturbs the host that drives
 * them; [DrivingCommand] changes them.
 */
abstract class RobotCommand(name: String, private val extra: IntRange = 0..0) : CoreCliktCommand(name) {
    private val globals by requireObject<Globals>()
    private val format by formatOptions()
    private val broker by brokerOptions()
    private val all by option("--all", help = "every robot found").flag()
    private val words by argument("ROBOT ARGS").multiple()

    /** True when the command runs on every robot found. */
    protected val allRobots: Boolean get() = all

    /** The arguments after the robot. */
    protected val rest: List<String> get() = if (all) words else words.drop(1)

    // Negative numbers are arguments (`move R rotate -90`): Clikt hands tokens it knows no option for to the
    // arguments, and those that are no number are refused here as the unknown options they are.
    override val treatUnknownOptionsAsArgs: Boolean = true

    override fun run() {
        words.firstOrNull { it.startsWith("-") && it.toDoubleOrNull() == null }?.let { throw NoSuchOption(it) }
        val names = if (all) emptyList() else listOfNotNull(words.firstOrNull())
        if (rest.size !in extra) throw UsageError("wrong number of arguments: ${words.joinToString(" ")}")
        try { check() } catch (e: IllegalArgumentException) { throw UsageError(e.message ?: "bad arguments") }
        robotCommand(globals.with(broker), format, names, all, role(), mustDrive(), onLeave()) { robots, out -> act(robots, out) }
    }

    /** What the command asks to be on the robots: it watches unless it changes them. */
    protected open fun role(): Role = Role.WATCH

    /** True when the command cannot do its work without driving the robots. */
    protected open fun mustDrive(): Boolean = false

    /** What the robots do with what the command queued once it leaves. */
    protected open fun onLeave(): QueueOnLeave = QueueOnLeave.FINISH

    /** Checks the arguments before any robot is looked for. */
    protected open fun check() {}

    protected abstract suspend fun CoroutineScope.act(robots: List<Robot>, out: Output)

    /** Runs [each] on every robot at once. */
    protected suspend fun CoroutineScope.onEach(robots: List<Robot>, each: suspend (Robot) -> Unit) =
        robots.map { r -> async { each(r) } }.awaitAll()
}

/**
 * A command that changes the robots: it drives them, and fails (exit 8) when another host drives one, unless
 * `--take-over` takes it (that host is told).
 */
abstract class DrivingCommand(name: String, extra: IntRange = 0..0) : RobotCommand(name, extra) {
    protected val takeOver by option("--take-over", help = "take the robot from the host that drives it (it is told, and watches)").flag()

    override fun role(): Role = if (takeOver) Role.TAKE_OVER else Role.DRIVE

    override fun mustDrive(): Boolean = true
}

class ScanCommand : CoreCliktCommand(name = "scan") {
    override fun help(context: Context) = "Lists the robots every source finds, one line each.\n\nExample: pocketbot scan --json"
    private val globals by requireObject<Globals>()
    private val format by formatOptions()
    private val broker by brokerOptions()

    override fun run() {
        val sources = globals.with(broker).sources
        val out = Output(format ?: globals.format)
        val progress = Progress()
        progress.show("looking for robots")
        val found = runBlocking {
            val broker = sources.broker?.let { options ->
                try { connectBroker(options) } catch (e: BrokerException) {
                    progress.clear()
                    System.err.println("pocketbot: ${e.message}")
                    throw ProgramResult(Exit.FAILED)
                }
            }
            try { sources.scan(broker, problem = { System.err.println("pocketbot: $it") }) } finally { broker?.close() }
        }
        progress.clear()
        for (f in found) out.row("name" to f.name, "address" to f.device.address, "source" to f.source)
        out.flush()
        if (found.isEmpty()) {
            System.err.println("pocketbot: no robots found")
            throw ProgramResult(Exit.NO_SUCH_ROBOT)
        }
    }
}

class InfoCommand : RobotCommand("info") {
    override fun help(context: Context) = "Identity, firmware and protocol version, layout hash, the host that drives it, and link of a robot.\n\nExample: pocketbot info PocketBot-1"

    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) {
        // The battery comes with the first full state after the handshake; a robot that sends none shows no battery.
        // Waited for on every robot at once: a fleet of silent robots costs one timeout, not one each.
        val states = robots.map { r -> async { withTimeoutOrNull(FIRST_STATE) { r.reportedState() } } }.awaitAll()
        for ((r, state) in robots.zip(states)) {
            val id = r.identity
            val stats = r.linkStats.value
            out.row(
                "name" to id.name, "id" to id.robotId, "address" to id.address, "firmware" to id.firmwareVersion,
                "protocol" to id.protocolVersion, "layout" to "0x" + id.layoutHash.toString(16).uppercase(),
                "battery_v" to state?.let { it.power.batteryMv / 1000.0 }, "driver" to r.driving.value.driver,
                "frames_in" to stats.framesReceived, "frames_out" to stats.framesSent, "dropped" to stats.dropped, "reconnects" to stats.reconnects,
            )
        }
    }
}

private val FIRST_STATE = kotlin.time.Duration.parse("2s")

class SettingsCommand : CoreCliktCommand(name = "settings") {
    override fun help(context: Context) = "Reads and writes a robot's settings by dotted name (line_pid.kp).\n\nExample: pocketbot settings list PocketBot-1"
    override fun run() {}

    init {
        subcommands(SettingsList(), SettingsGet(), SettingsSet(), SettingsSave(), SettingsDefaults(), SettingsExport(), SettingsImport())
    }
}

private fun field(robot: Robot, name: String): SettingField<*> =
    robot.settings[name] ?: throw IllegalArgumentException("no setting '$name' (see: pocketbot settings list)")

/**
 * The value as people read it and scripts get it: a real number as the robot's binary32 float (printed as its
 * shortest decimal, 0.0004, and a number in JSON), an enumeration by name, a list as a list.
 */
private fun shown(f: SettingField<*>): Any? = (f.value as? Double)?.toFloat() ?: f.value

class SettingsList : RobotCommand("list", 0..1) {
    override fun help(context: Context) = "Every setting (or those of a GROUP) with value, unit, range and what it does.\n\nExample: pocketbot settings list PocketBot-1 line_pid"

    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) {
        val group = rest.firstOrNull()
        for (r in robots) {
            val fields = r.settings.fields.filter { group == null || it.name.startsWith("$group.") || it.name == group }
            if (fields.isEmpty()) throw IllegalArgumentException("no settings group '$group'")
            for (f in fields) {
                out.row(linkedMapOf("robot" to r.label, "name" to f.name, "value" to shown(f), "unit" to f.unit, "range" to f.rangeText, "doc" to f.doc)
                    .also { if (robots.size == 1) it.remove("robot") })
            }
        }
    }
}

class SettingsGet : RobotCommand("get", 1..Int.MAX_VALUE) {
    override fun help(context: Context) = "The value of each NAME.\n\nExample: pocketbot settings get PocketBot-1 line_pid.kp line_pid.kd"

    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) {
        for (r in robots) for (name in rest) {
            val f = field(r, name)
            out.row("robot" to r.label, "name" to f.name, "value" to shown(f), "unit" to f.unit)
        }
    }
}

class SettingsSet : DrivingCommand("set", 2..2) {
    override fun help(context: Context) = """
        Writes NAME = VALUE (that field only) and reports the robot's acknowledgement, or its refusal (exit 4).

        Example: pocketbot settings set PocketBot-1 line_pid.kp 1.5
    """.trimIndent()

    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) {
        val (name, text) = rest
        onEach(robots) { r ->
            @Suppress("UNCHECKED_CAST")
            val f = field(r, name) as SettingField<Any>
            val value = f.parse(text)
            f.set(value)
            out.row("robot" to r.label, "name" to f.name, "value" to shown(f), "status" to "acknowledged")
        }
    }
}

class SettingsSave : DrivingCommand("save") {
    override fun help(context: Context) = "Saves the robot's settings to its EEPROM (they survive a reset).\n\nExample: pocketbot settings save --all"
    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) = onEach(robots) { r ->
        r.settings.save()
        out.row("robot" to r.label, "status" to "saved")
    }.let { }
}

class SettingsDefaults : DrivingCommand("defaults") {
    override fun help(context: Context) = "Loads the firmware's default settings (not saved until 'settings save').\n\nExample: pocketbot settings defaults PocketBot-1"
    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) = onEach(robots) { r ->
        r.settings.loadDefaults()
        out.row("robot" to r.label, "status" to "defaults loaded")
    }.let { }
}

/** With --all, settings files live in a directory, one per robot, named after the robot. */
private fun fileOf(dir: File, robot: Robot): File = File(dir, robot.label.replace(Regex("[^A-Za-z0-9._-]"), "_") + ".json")

class SettingsExport : RobotCommand("export", 0..1) {
    override fun help(context: Context) = """
        Writes every setting as JSON to FILE, or to stdout.

        With --all, writes one file per robot into the directory DIR, named after the robot (DIR/PocketBot-1.json):
        a robot's settings include its id and name, so robots never share one file.

        Example: pocketbot settings export PocketBot-1 robot1.json
    """.trimIndent()

    override fun check() {
        if (allRobots && rest.isEmpty()) throw UsageError("with --all, name a directory: one file per robot goes into it")
    }

    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) {
        val target = rest.firstOrNull()?.let(::File)
        if (!allRobots) {
            val json = robots.single().settings.exportJson()
            if (target == null) println(json) else target.writeText(json)
            return
        }
        target!!.mkdirs()
        for (r in robots) {
            val file = fileOf(target, r)
            file.writeText(r.settings.exportJson())
            out.row("robot" to r.label, "file" to file.path)
        }
    }
}

class SettingsImport : DrivingCommand("import", 1..1) {
    override fun help(context: Context) = """
        Writes the settings in the JSON FILE (the export format; settings may be left out).

        Nothing is written when the file does not parse; when the robot refuses a value, the values written before it
        are put back (exit 4).
        With --all, FILE is a directory of 'settings export --all': each robot gets its own file, and nothing is
        written unless every robot has one.

        Example: pocketbot settings import PocketBot-1 robot1.json
    """.trimIndent()

    private val path by lazy { File(rest.single()) }

    override fun check() {
        if (allRobots && !path.isDirectory) throw UsageError("with --all, name the directory 'settings export --all' wrote")
        if (!allRobots && !path.isFile) throw UsageError("no file ${path.path}")
    }

    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) {
        val texts = robots.associateWith { r ->
            val file = if (allRobots) fileOf(path, r) else path
            if (!file.isFile) throw IllegalArgumentException("no settings file ${file.path} for ${r.label}")
            file.readText()
        }
        onEach(robots) { r ->
            val before = r.settings.exportJson()
            val written = try {
                r.settings.importJson(texts.getValue(r))
            } catch (e: org.pocketbot.sdk.SettingRefusedException) {
                r.settings.importJson(before)
                throw e
            }
            out.row("robot" to r.label, "written" to written, "status" to "imported")
        }
    }
}

class StateCommand : DrivingCommand("state") {
    override fun help(context: Context) = """
        Prints the robot's state once, or with --watch every state the robot sends until stopped. It only watches the
        robot; --rate HZ asks it for that many full states a second (driving it to ask; while another host drives it,
        its states come as that host chose them, unless --take-over).

        By default a few values in people's units: robot time, locomotion mode, speed, line position, battery and the
        pose (x, y, heading: dead reckoning from the encoders since this command connected). --fields picks state
        fields or groups (wheels, line.position, ...), pose, or all.

        Example: pocketbot state PocketBot-1 --watch --rate 20 --fields time.time_ms,wheels,pose --csv
    """.trimIndent()

    private val watch by option("--watch", help = "keep printing until Ctrl-C (or --seconds)").flag()
    private val rate by option("--rate", help = "full states per second while watching, 1..100 (the robot's own rate when not given)").int().restrictTo(1..100)
    private val seconds by option("--seconds", help = "stop watching after this many seconds").double()
    private val fields by option("--fields", help = "comma-separated state fields or groups, pose, or all").split(",")

    private val selected by lazy { fields?.let(StateColumns::select) ?: StateColumns.readable }

    override fun role(): Role = if (rate != null) super.role() else Role.WATCH
    override fun mustDrive(): Boolean = false

    override fun check() {
        selected // an unknown field is a usage error before any robot is looked for
    }

    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) {
        fun print(r: Robot, s: RobotState) = out.row(linkedMapOf<String, Any?>("robot" to r.label).apply {
            for (c in selected) put(c.name, c.of(r, s))
        })
        if (!watch) {
            // The mirror is all zero until the robot's first state: print what the robot reported, not that.
            val states = robots.map { r -> async { withTimeout(FIRST_STATE) { r.reportedState() } } }.awaitAll()
            robots.zip(states).forEach { (r, s) -> print(r, s) }
            return
        }
        rate?.let { hz ->
            onEach(robots) { r ->
                if (r.driving.value.byThisHost) r.reflector.set(SyncMode.FULL, (1000 / hz).milliseconds)
                else System.err.println("pocketbot: ${r.label} is driven by ${r.driving.value.driver}: its state comes as that host chose (--take-over to set the rate)")
            }
        }
        out.stream(linkedMapOf("robot" to robots.maxOf { it.label.length }) + selected.associate { it.name to it.width })
        withTimeoutOrNull(seconds?.let { (it * 1000).toLong().milliseconds } ?: kotlin.time.Duration.INFINITE) {
            val printers = robots.map { r -> launch { r.stateUpdates.collect { print(r, it.state) } } }
            val gone = firstLost(robots)
            printers.forEach { it.cancel() }
            throw LinkLostException("lost the link to ${gone.label}: ${describe(gone.connection.value)}")
        }
    }
}

/** Suspends until one of [robots] loses its link, and returns that one. */
private suspend fun firstLost(robots: List<Robot>): Robot = channelFlow {
    for (r in robots) launch { r.connection.first { it is ConnectionState.Lost || it is ConnectionState.Closed }; send(r) }
}.first()

class ConsoleCommand : DrivingCommand("console") {
    override fun help(context: Context) = """
        Prints the robot's debug text, and the SDK's messages about its link, until stopped. It only watches the robot.

        --level sets the robot's debug level first (1 errors, 2 info, 3 verbose, 4 trace), driving it to do so and then
        only watching (a host that waits to drive it gets it back); while another host drives it, the level stays as
        it is, unless --take-over.

        Example: pocketbot console PocketBot-1 --level 3
    """.trimIndent()

    private val level by option("--level", help = "the robot's debug level, 1..4").int().restrictTo(1..4)
    private val seconds by option("--seconds", help = "stop after this many seconds").double()

    override fun role(): Role = if (level != null) super.role() else Role.WATCH
    override fun mustDrive(): Boolean = false

    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) {
        level?.let { l ->
            onEach(robots) { r ->
                if (r.driving.value.byThisHost) {
                    r.settings.debug.level.set(l)
                    r.setRole(Role.WATCH) // reading the console needs no drive: the robot is free for other hosts
                } else System.err.println("pocketbot: ${r.label} is driven by ${r.driving.value.driver}: its debug level stays (--take-over to set it)")
            }
        }
        out.stream(linkedMapOf(
            "robot" to robots.maxOf { it.label.length }, "level" to 1,
            "source" to (DebugModule.entries + DebugSource.entries).maxOf { it.name.length }, "text" to 0,
        ))
        withTimeoutOrNull(seconds?.let { (it * 1000).toLong().milliseconds } ?: kotlin.time.Duration.INFINITE) {
            val printers = robots.map { r ->
                launch { r.debugLog.messages.collect { m -> out.row("robot" to r.label, "level" to m.level, "source" to (m.module?.name?.lowercase() ?: m.source.name.lowercase()), "text" to m.text) } }
            }
            val gone = firstLost(robots)
            printers.forEach { it.cancel() }
            throw LinkLostException("lost the link to ${gone.label}: ${describe(gone.connection.value)}")
        }
    }
}

class MoveCommand : DrivingCommand("move", 2..3) {
    override fun help(context: Context) = """
        Queues a movement: 'straight DISTANCE_M', 'rotate ANGLE_DEG' or 'arc RADIUS_M ANGLE_DEG', at --speed m/s.
        It ends line following or the track behaviour if the robot runs one (and says so).

        With --wait, returns when it ended and prints how and how much of it was done (exit 0 only when it finished;
        5 when the link failed it). A link that stays down for ${LINK_GRACE.inWholeSeconds} s ends the wait: the movement is
        then 'lost', with what this host saw the robot do before (the robot's failsafe stops it on its own).
        Without it, pocketbot leaves at once, saying goodbye: the robot finishes the movement (--on-leave drop: it
        drops it). A pocketbot killed before its goodbye leaves the robot to its link failsafe, which stops it.

        Example: pocketbot move PocketBot-1 straight 0.2 --speed 0.15 --wait
    """.trimIndent()

    private val speed by option("--speed", help = "cruise speed, m/s").double().default(0.2)
    private val wait by option("--wait", help = "return when the movement ended").flag()
    private val leave by option("--on-leave", help = "what the robot does with the movement when pocketbot leaves before it ended: finish (default) or drop")
        .choice("finish" to QueueOnLeave.FINISH, "drop" to QueueOnLeave.DROP).default(QueueOnLeave.FINISH)

    override fun onLeave(): QueueOnLeave = leave

    private val movement by lazy {
        val numbers = rest.drop(1).map { it.toDoubleOrNull() ?: throw UsageError("'$it' is not a number") }
        // The speed is an option: a number after the amount is most likely meant as one.
        fun one(): Double = numbers.singleOrNull()
            ?: throw UsageError("${rest.first()} wants one number, not ${numbers.size}" + if (numbers.size > 1) " (the speed is --speed)" else "")
        try {
            when (rest.first()) {
                "straight" -> Movement.Straight(one(), speed)
                "rotate" -> Movement.Rotate(one(), speed)
                "arc" -> if (numbers.size == 2) Movement.Arc(numbers[0], numbers[1], speed) else throw UsageError("arc wants RADIUS_M ANGLE_DEG")
                else -> throw UsageError("movement is straight, rotate or arc, not '${rest.first()}'")
            }
        } catch (e: IllegalArgumentException) {
            throw UsageError(e.message ?: "bad movement")
        }
    }

    override fun check() { movement }

    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) {
        val moves = robots.map { r -> async { start(r) } }.awaitAll()
        if (!wait) {
            for (m in moves) {
                out.row("robot" to m.robot.label, "id" to m.handle.id, "movement" to movement.toString(), "status" to "queued",
                    "on_leave" to if (leave == QueueOnLeave.FINISH) "the robot finishes it" else "the robot drops it")
            }
            return
        }
        val results = try {
            moves.map { m -> async { m.handle.await().also { out.row(m.row(it)) } } }.awaitAll()
        } catch (e: CancellationException) {
            // A link stayed down (the command ends with exit 5): each movement still open, as far as this host saw it.
            for (m in moves) if (!m.handle.isDone) out.row(m.row(null))
            throw e
        }
        out.flush()
        when {
            results.any { it.outcome == MovementOutcome.FAILSAFE || it.outcome == MovementOutcome.LOST } -> throw ProgramResult(Exit.LINK_LOST)
            results.any { it.outcome != MovementOutcome.FINISHED } -> throw ProgramResult(Exit.FAILED)
        }
    }

    /** Queues the movement on [r], saying so when that ends the line following or track behaviour the robot ran. */
    private suspend fun start(r: Robot): Started {
        val mode = withTimeoutOrNull(FIRST_STATE) { r.reportedState() }?.locomotion?.mode
        val started = Started(r, r.locomotion.enqueue(movement), r.odometry.wheelDistances.value)
        when (mode) {
            LocoMode.LINE_FOLLOW -> System.err.println("pocketbot: ${r.label} was following the line: the movement ended that")
            LocoMode.TRACK -> System.err.println("pocketbot: ${r.label} ran the track behaviour: the movement ended that")
            else -> {}
        }
        return started
    }

    /** A movement the robot took, and its wheel distances then. */
    private inner class Started(val robot: Robot, val handle: MovementHandle, val wheels: WheelDistances) {
        /**
         * How much of it this host saw the robot do, from the odometry since the robot took it: metres for a straight,
         * degrees for a rotation or an arc. For a movement whose end is not known (its robot was lost).
         */
        fun seen(): Double = when (movement) {
            is Movement.Straight -> robot.odometry.wheelDistances.value.let { (it.leftM + it.rightM - wheels.leftM - wheels.rightM) / 2 }
            // From the wheels, not the heading: a heading reads -180..180 degrees, a turn may be larger.
            else -> robot.odometry.wheelDistances.value.let {
                Math.toDegrees((it.rightM - it.leftM - wheels.rightM + wheels.leftM) / robot.settings.geometry.wheelBaseM.value)
            }
        }.let { kotlin.math.round(it * 1000) / 1000 }

        /** Its row: how it ended, or with [result] null `lost` and what [seen] says. */
        fun row(result: MovementResult?): Map<String, Any?> = linkedMapOf(
            "robot" to robot.label, "id" to handle.id, "movement" to movement.toString(),
            "outcome" to (result?.outcome ?: MovementOutcome.LOST),
            // The robot's own figure is a float: as it says it. Without one, what this host saw.
            "done" to (result?.done?.toFloat() ?: seen()), "unit" to movement.unit.symbol,
        )
    }
}

class StopCommand : RobotCommand("stop") {
    override fun help(context: Context) = "Stops the robot: brakes along its profile, or with --now turns the motors off. Any host may stop a robot: no --take-over is needed, and the host that drives it keeps driving.\n\nExample: pocketbot stop --all"
    private val now by option("--now", help = "motors off at once").flag()
    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) = onEach(robots) { r ->
        r.locomotion.stop(immediate = now)
        out.row("robot" to r.label, "status" to "stopped")
    }.let { }
}

class FollowCommand : DrivingCommand("follow", 1..1) {
    override fun help(context: Context) = """
        Starts or stops line following: 'start' or 'stop'.

        --speed m/s (default: the robot's setting), --colours for colour segments (red slows down, blue speeds up).

        Example: pocketbot follow PocketBot-1 start --speed 0.15 --colours
    """.trimIndent()

    private val speed by option("--speed", help = "m/s").double()
    private val colours by option("--colours", help = "colour segments mode").flag()

    override fun check() {
        if (rest.single() !in setOf("start", "stop")) throw UsageError("follow start or follow stop, not '${rest.single()}'")
    }

    override suspend fun CoroutineScope.act(robots: List<Robot>, out: Output) = onEach(robots) { r ->
        if (rest.single() == "start") r.lineFollower.start(speed, if (colours) ColourMode.SEGMENTS else ColourMode.PLAIN)
        else r.lineFollower.stop()
        out.row("robot" to r.label, "status" to if (rest.single() == "start") "following" else "stopped")
    }.let { }
}

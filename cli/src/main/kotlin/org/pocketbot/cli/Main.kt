package org.pocketbot.cli

import com.github.ajalt.clikt.core.CliktError
import com.github.ajalt.clikt.core.Context
import com.github.ajalt.clikt.core.CoreCliktCommand
import com.github.ajalt.clikt.core.UsageError
import com.github.ajalt.clikt.core.obj
import com.github.ajalt.clikt.core.parse
import com.github.ajalt.clikt.core.subcommands
import com.github.ajalt.clikt.parameters.groups.provideDelegate
import com.github.ajalt.clikt.parameters.options.default
import com.github.ajalt.clikt.parameters.options.flag
import com.github.ajalt.clikt.parameters.options.option
import com.github.ajalt.clikt.parameters.options.split
import com.github.ajalt.clikt.parameters.options.switch
import com.github.ajalt.clikt.parameters.types.double
import com.github.ajalt.clikt.parameters.types.int
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.TimeoutCancellationException
import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import org.pocketbot.emulator.cli.BrokerFlags
import org.pocketbot.emulator.cli.EmulatorCommand
import org.pocketbot.sdk.CommandRefusedException
import org.pocketbot.sdk.CommandTimeoutException
import org.pocketbot.sdk.ConnectFailedException
import org.pocketbot.sdk.HostLabel
import org.pocketbot.sdk.NotDriverException
import org.pocketbot.sdk.QueueOnLeave
import org.pocketbot.sdk.Role
import org.pocketbot.sdk.ProtocolMismatchException
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotClosedException
import org.pocketbot.sdk.RobotEvent
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.transport.EmulatorDiscoverer
import org.pocketbot.sdk.mqtt.BrokerClient
import org.pocketbot.sdk.mqtt.connectBroker
import org.pocketbot.sdk.transport.TransportLostException
import kotlin.system.exitProcess
import kotlin.time.Duration.Companion.milliseconds

/** The documented exit codes (README, `pocketbot --help`). */
object Exit {
    const val OK = 0
    const val FAILED = 1
    const val USAGE = 2
    const val NO_SUCH_ROBOT = 3
    const val REFUSED = 4
    const val LINK_LOST = 5
    const val VERSION_MISMATCH = 6
    const val TIMEOUT = 7
    const val DRIVEN_ELSEWHERE = 8

    /** The exit code for [e], the way a script can act on it. */
    fun of(e: Throwable): Int = when (e) {
        is NoSuchRobotException -> NO_SUCH_ROBOT
        is NotDriverException, is DrivenElsewhereException -> DRIVEN_ELSEWHERE
        is CommandRefusedException -> REFUSED
        is ProtocolMismatchException -> VERSION_MISMATCH
        is CommandTimeoutException, is TimeoutCancellationException -> TIMEOUT
        // A robot that is reached but never answers its hello timed out; one that cannot be reached lost its link.
        is ConnectFailedException -> if (generateSequence(e.cause) { it.cause }.any { it is CommandTimeoutException }) TIMEOUT else LINK_LOST
        is RobotClosedException, is TransportLostException, is LinkLostException -> LINK_LOST
        is IllegalArgumentException -> USAGE
        else -> FAILED
    }
}

/** What every command shares: where to look for robots, and how to print. */
class Globals(val format: Format, val sources: Sources) {
    val options = RobotOptions { hostLabel = HostLabel.of("cli") }

    /**
     * These, with the broker a command's own [flags] name (`pocketbot scan --broker URL`) if they name one.
     *
     * @throws UsageError for `--sources broker` without a broker.
     */
    fun with(flags: BrokerFlags): Globals {
        val merged = flags.options()?.let { Globals(format, sources.through(it)) } ?: this
        if ("broker" in merged.sources.kinds && merged.sources.broker == null) throw UsageError("--sources broker needs --broker URL", "--sources")
        return merged
    }
}

/** Another host drives the robot and the command would change it: exit code 8. */
class DrivenElsewhereException(message: String) : Exception(message)

/** `--broker` and its credentials, accepted before the command (for every command) and after it. */
fun brokerOptions() = BrokerFlags()

/** `--json` / `--csv`, accepted before the command (for every command) and after it: the format, or null for the default. */
fun CoreCliktCommand.formatOptions() = option(help = "output format: --json (one object per line) or --csv").switch("--json" to Format.JSON, "--csv" to Format.CSV)

class PocketBot : CoreCliktCommand(name = "pocketbot") {
    override fun help(context: Context) = """
        Scripts PocketBot robots and fleets: find them, read and write their settings, watch their state and debug
        text, move them. A robot is named by its name, its id or its address (tcp://127.0.0.1:40001 or
        serial:/dev/rfcomm0 need no scan); --all runs a command on every robot found. With --broker the robots of
        other hosts are found too, through an MQTT broker, each named GATEWAY/ROBOT (pocketbot gateway serves them);
        --broker and its credentials go before the command or after it, like --json.

        Exit codes: 0 ok, 1 other failure, 2 usage (also an unknown setting or field), 3 no such robot,
        4 refused by the robot, 5 link lost (also a link that stays down for ${LINK_GRACE.inWholeSeconds} s: no command waits longer
        for it), 6 firmware version mismatch, 7 timeout, 8 driven by another host (commands that change a robot need
        --take-over then; the others only watch it).

        Examples: pocketbot settings set PocketBot-1 line_pid.kp 1.5
                  pocketbot --broker mqtts://central:8883 --ca ca.crt --user alice move lab1/PocketBot-1 straight 0.1
    """.trimIndent()

    private val format by formatOptions().default(Format.TABLE)
    private val host by option(help = "host of the emulator's control port").default("127.0.0.1")
    private val controlPort by option("--control-port", help = "the emulator's control port").int().default(EmulatorDiscoverer.DEFAULT_CONTROL_PORT)
    private val sources by option("--sources", help = "where to look: emulator, serial, bluetooth, broker (comma-separated; --broker adds the broker)")
        .split(",").default(listOf("emulator", "serial", "bluetooth"))
    private val scanSeconds by option("--scan-seconds", help = "how long to look for robots").double().default(3.0)
    private val broker by brokerOptions()

    override fun run() {
        val unknown = sources - setOf("emulator", "serial", "bluetooth", "broker")
        if (unknown.isNotEmpty()) throw UsageError("unknown source ${unknown.joinToString()}", "--sources")
        currentContext.obj = Globals(
            format,
            Sources(host, controlPort, sources.toSet(), (scanSeconds * 1000).toLong().milliseconds, broker.options()),
        )
    }
}

/** Runs the command line and returns its exit code (the tests call this too, in process or through [main]). */
fun run(args: Array<String>): Int {
    val command = PocketBot().subcommands(
        ScanCommand(), InfoCommand(), SettingsCommand(), StateCommand(), ConsoleCommand(),
        MoveCommand(), StopCommand(), FollowCommand(), EmulatorCommand(), GatewayCommand(),
    )
    return try {
        command.parse(args)
        Exit.OK
    } catch (e: CliktError) {
        // Help asked for goes to stdout; errors to stderr, where a script does not mistake them for output.
        command.getFormattedHelp(e)?.let { if (e.printError) System.err.println(it) else println(it) }
        if (e is UsageError) Exit.USAGE else e.statusCode
    }
}

/** What happened to a robot while a command ran, on stderr: a script's output stays clean. */
private fun tell(robot: Robot, event: RobotEvent) = when (event) {
    is RobotEvent.Restarted ->
        System.err.println("pocketbot: ${robot.label} restarted: its clock went back from ${event.lastSeenTimeMs / 1000.0} s to ${event.timeMs / 1000.0} s")
    is RobotEvent.DriverChanged ->
        if (event.taken) System.err.println("pocketbot: ${robot.label} was taken over by ${event.driving.driver}") else Unit
}

fun main(args: Array<String>) {
    exitProcess(run(args))
}

/**
 * Runs [block] with the robots a command names connected as [role], and says goodbye to them afterwards (the robot
 * does with what this command queued as [onLeave] says). With [mustDrive], a robot that another host drives fails
 * the command before anything is sent to any robot. Failures become a clear line on stderr and the documented exit
 * code. A robot whose link stays down for [LINK_GRACE] (or closes) ends the command with exit 5: the SDK would wait
 * for the link without end, and a command must end.
 */
fun robotCommand(
    globals: Globals, format: Format?, names: List<String>, all: Boolean, role: Role, mustDrive: Boolean, onLeave: QueueOnLeave,
    block: suspend CoroutineScope.(List<Robot>, Output) -> Unit,
) {
    if (!all && names.isEmpty()) throw UsageError("name a robot, or use --all")
    val out = Output(format ?: globals.format)
    val code = runBlocking {
        val progress = Progress()
        var robots = emptyList<Robot>()
        var listening = emptyList<Job>()
        var broker: BrokerClient? = null
        try {
            progress.show("looking for robots")
            broker = globals.sources.broker?.let { connectBroker(it) }
            // Robots named by name or address end the search once all are found; ids and --all need the whole scan;
            // robots named only by their addresses need none.
            val found = if (!all && names.all { deviceAt(it) != null }) emptyList() else globals.sources.scan(broker, enough = { f ->
                !all && names.all { n -> f.any { it.answersTo(n) } }
            })
            robots = connectRobots(found, names, all, RobotOptions(globals.options) { this.role = role }, progress, broker)
            listening = robots.map { r -> launch { r.events.collect { tell(r, it) } } }
            if (mustDrive) robots.firstOrNull { !it.driving.value.byThisHost }?.let { r ->
                throw DrivenElsewhereException("${r.label} is driven by ${r.driving.value.driver ?: "no host"} (use --take-over)")
            }
            coroutineScope { // a failure of any robot's part surfaces as itself
                val watch = launch { throw linkGone(robots) }
                try { block(robots, out) } finally { watch.cancel() }
            }
            out.flush()
            Exit.OK
        } catch (e: CliktError) {
            throw e
        } catch (e: Exception) {
            progress.clear()
            out.flush()
            System.err.println("pocketbot: ${e.message ?: e}" + if (e is NotDriverException) " (use --take-over)" else "")
            Exit.of(e)
        } finally {
            listening.forEach { it.cancel() }
            for (r in robots) r.disconnect(onLeave)
            broker?.close()
        }
    }
    if (code != Exit.OK) throw com.github.ajalt.clikt.core.ProgramResult(code)
}

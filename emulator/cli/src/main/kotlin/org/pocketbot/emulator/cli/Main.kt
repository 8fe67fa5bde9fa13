package org.pocketbot.emulator.cli

import com.github.ajalt.clikt.core.Context
import com.github.ajalt.clikt.core.CoreCliktCommand
import com.github.ajalt.clikt.core.UsageError
import com.github.ajalt.clikt.core.CliktError
import com.github.ajalt.clikt.core.parse
import com.github.ajalt.clikt.parameters.options.convert
import com.github.ajalt.clikt.parameters.options.default
import com.github.ajalt.clikt.parameters.options.option
import com.github.ajalt.clikt.parameters.types.int
import com.github.ajalt.clikt.parameters.types.long
import com.github.ajalt.clikt.parameters.types.restrictTo
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.EmulatorConfig
import org.pocketbot.emulator.SimTime
import org.pocketbot.emulator.Speed
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.emulator.world.Worlds
import java.io.IOException
import kotlin.system.exitProcess

/**
 * The emulator as a command: robots on TCP ports and a control port listing them. `make emulator` runs it, and the
 * `pocketbot` command line offers it as `pocketbot emulator`.
 */
public class EmulatorCommand : CoreCliktCommand(name = "emulator") {
    override fun help(context: Context): String = """
        Runs emulated PocketBot2 robots (the real firmware as WebAssembly) on TCP ports, until stopped.

        Ctrl-C or 'q' on stdin stops it. Only this machine reaches the robots unless --listen puts them on the
        network. Stdin commands: p pause, r resume, s single step, t time, q quit.

        Examples: emulator --robots 3 --world round
                  emulator --listen 0.0.0.0      (a phone on the same Wi-Fi drives the robots)
    """.trimIndent()

    private val robots by option(help = "robots to start, ids 1..N, at the world's start poses").int().restrictTo(1..254).default(1)
    private val world by option(help = "a shipped world (${Worlds.names.joinToString()}) or a world file").default("straight")
    private val seed by option(help = "seed of every random effect").long().default(1)
    private val speed by option(help = "simulated seconds per wall-clock second, or max").default("1")
    private val listen by option("--listen", metavar = "ADDRESS",
        help = "the address to listen on: 127.0.0.1 (only this machine), 0.0.0.0 (every address: the network) or one address of this machine")
        .convert { text -> try { ListenAddress.parse(text) } catch (e: IllegalArgumentException) { fail(e.message ?: text) } }
        .default(ListenAddress.LOOPBACK, defaultForHelp = "127.0.0.1")
    private val portBase by option("--port-base", help = "robot i listens on port P+i-1 (0 = any free port)").int().default(40001)
    private val controlPort by option("--control-port", help = "control port listing the robots (0 = any free port, -1 = none)").int().default(40000)
    private val threads by option(help = "threads stepping the robots").int().restrictTo(min = 1).default(EmulatorConfig().threads)

    override fun run() {
        val pace = if (speed == "max") Speed.AsFastAsPossible
        else Speed.Realtime(speed.toDoubleOrNull()?.takeIf { it > 0 } ?: throw UsageError("--speed wants a positive number or max", "--speed"))
        val w = try { Worlds.load(world) } catch (e: Exception) { throw UsageError("cannot load world $world: ${e.message}", "--world") }
        val emu = Emulator(w, EmulatorConfig(seed = seed, threads = threads)).also { e ->
            try { repeat(robots) { e.addRobot() } } catch (full: IllegalStateException) { e.close(); throw CliktError(full.message) }
        }
        val control = try {
            emu.startTcp(basePort = portBase, controlPort = controlPort, listen = listen)
        } catch (e: IOException) {
            emu.close()
            throw CliktError("cannot listen on ${ListenAddress.hostText(listen)}: ${e.message}")
        }
        // The lines name an address other programs reach: on the wildcard address, this machine's best network address.
        val reachable = ListenAddress.reachable(listen)
        val host = ListenAddress.hostText(reachable.first())
        val where = if (listen.isLoopbackAddress) "" else
            ", on the network at ${reachable.joinToString { ListenAddress.hostText(it) }} (anyone there can drive these robots)"
        println("PocketBot emulator: world ${w.name}, $robots robot(s), seed $seed, speed ${describe(pace)}, firmware ${emu.firmwareEngine.name.lowercase()}$where")
        for (r in emu.robots) println("robot ${r.id} ${r.name} tcp $host:${r.tcpPort}")
        if (control >= 0) println("control $host:$control")
        System.out.flush()
        Runtime.getRuntime().addShutdownHook(Thread { emu.close() })
        emu.start(pace)
        val input = System.`in`.bufferedReader()
        while (true) {
            val line = try { input.readLine() } catch (_: Exception) { null }
            if (line == null) { Thread.sleep(Long.MAX_VALUE); continue } // no stdin (e.g. in the background): run until killed
            when (line.trim()) {
                "p" -> { emu.pause(); println("paused at ${emu.time}") }
                "r" -> { emu.resume(); println("running") }
                "s" -> { emu.pause(); emu.singleStep(); println("t=${emu.time}") }
                "t" -> println("t=${emu.time} (${emu.timeTicks} ticks of ${SimTime.TICKS_PER_SECOND} Hz)")
                "q" -> { emu.close(); exitProcess(0) }
                "" -> {}
                else -> println("commands: p pause, r resume, s single step, t time, q quit")
            }
        }
    }

    private fun describe(s: Speed) = when (s) {
        Speed.AsFastAsPossible -> "max"
        is Speed.Realtime -> "x${s.factor}"
    }
}

/** Runs the emulator command; a usage error exits with 2, as every PocketBot command line does. */
public fun main(args: Array<String>) {
    val command = EmulatorCommand()
    try {
        command.parse(args)
    } catch (e: CliktError) {
        command.getFormattedHelp(e)?.let { if (e.printError) System.err.println(it) else println(it) }
        exitProcess(if (e is UsageError) 2 else e.statusCode)
    }
}

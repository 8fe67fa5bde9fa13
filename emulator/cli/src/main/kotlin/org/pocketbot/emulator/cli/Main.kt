package org.pocketbot.emulator.cli

import com.github.ajalt.clikt.core.Context
import com.github.ajalt.clikt.core.CoreCliktCommand
import com.github.ajalt.clikt.core.UsageError
import com.github.ajalt.clikt.core.CliktError
import com.github.ajalt.clikt.core.parse
import com.github.ajalt.clikt.parameters.groups.provideDelegate
import com.github.ajalt.clikt.parameters.options.convert
import com.github.ajalt.clikt.parameters.options.default
import com.github.ajalt.clikt.parameters.options.multiple
import com.github.ajalt.clikt.parameters.types.choice
import com.github.ajalt.clikt.parameters.options.option
import com.github.ajalt.clikt.parameters.types.int
import com.github.ajalt.clikt.parameters.types.long
import com.github.ajalt.clikt.parameters.types.restrictTo
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.EmulatorConfig
import org.pocketbot.emulator.SimTime
import org.pocketbot.emulator.Speed
import org.pocketbot.emulator.bluetooth.VirtualBluetooth
import org.pocketbot.emulator.firmware.FirmwareImage
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.emulator.world.Worlds
import org.pocketbot.sdk.mqtt.BrokerException
import org.pocketbot.sdk.mqtt.Gateway
import org.pocketbot.sdk.mqtt.startGateway
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeoutOrNull
import java.io.IOException
import java.net.InetSocketAddress
import kotlin.system.exitProcess
import kotlin.time.Duration.Companion.seconds

/**
 * The emulator as a command: robots on TCP ports and a control port listing them. `make emulator` runs it, and the
 * `pocketbot` command line offers it as `pocketbot emulator`.
 */
public class EmulatorCommand : CoreCliktCommand(name = "emulator") {
    override fun help(context: Context): String = """
        Runs emulated PocketBot2 robots (the real firmware as WebAssembly) on TCP ports, until stopped.

        Ctrl-C or 'q' on stdin stops it. Only this machine reaches the robots unless --listen puts them on the
        network. Stdin commands: p pause, r resume, s single step, t time, q quit.

        With --link hci every robot runs the firmware's HCI build and its UART carries H4 to a Bluetooth controller:
        virtual ones (Bumble) and a gateway whose TCP ports reach each robot over Bluetooth, or the controllers
        --h4 names (Bumble's HCI bridge in front of a USB dongle: then phones and computers reach the robots over
        real Bluetooth).

        With --broker and --gateway the robots are also served through an MQTT broker, under the gateway's name:
        programs on other hosts drive them there (pocketbot --broker URL ...).

        Examples: emulator --robots 3 --world round
                  emulator --listen 0.0.0.0      (a phone on the same Wi-Fi drives the robots)
                  emulator --robots 2 --link hci (each robot behind its own virtual Bluetooth controller)
                  emulator --robots 5 --broker mqtts://central:8883 --ca ca.crt --user lab1 --password-file lab1.pw --gateway lab1
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
    private val link by option("--link", help = "direct: the UART carries frames to TCP; hci: H4 to a Bluetooth controller")
        .choice("direct", "hci").default("direct")
    private val h4 by option("--h4", metavar = "HOST:PORT",
        help = "with --link hci: robot i drives the H4 controller at the i-th --h4 instead of a virtual one").multiple()
    private val gatewayName by option("--gateway", metavar = "NAME", help = "with --broker: the gateway's name, the robots' topics pb/v1/NAME/...")
    private val broker by BrokerFlags()

    override fun run() {
        val pace = if (speed == "max") Speed.AsFastAsPossible
        else Speed.Realtime(speed.toDoubleOrNull()?.takeIf { it > 0 } ?: throw UsageError("--speed wants a positive number or max", "--speed"))
        val w = try { Worlds.load(world) } catch (e: Exception) { throw UsageError("cannot load world $world: ${e.message}", "--world") }
        val hci = link == "hci"
        if (h4.isNotEmpty() && !hci) throw UsageError("--h4 needs --link hci", "--h4")
        // A Bluetooth controller answers on the wall clock: the robot's firmware must run on it too.
        if (hci && pace != Speed.Realtime(1.0)) throw UsageError("--link hci runs at --speed 1 only (controllers keep real time)", "--speed")
        if (h4.isNotEmpty() && h4.size != robots) throw UsageError("--h4 names ${h4.size} controller(s) for $robots robot(s)", "--h4")
        val brokerOptions = broker.options()
        if ((brokerOptions == null) != (gatewayName == null)) throw UsageError("--broker and --gateway go together", "--gateway")
        val firmware = if (hci) {
            try { FirmwareImage.compiledHci() } catch (e: IllegalStateException) { throw CliktError(e.message) }
        } else null
        val emu = Emulator(w, EmulatorConfig(seed = seed, threads = threads, firmware = firmware)).also { e ->
            try { repeat(robots) { e.addRobot() } } catch (full: IllegalStateException) { e.close(); throw CliktError(full.message) }
        }
        // The lines name an address other programs reach: on the wildcard address, this machine's best network address.
        val reachable = ListenAddress.reachable(listen)
        val host = ListenAddress.hostText(reachable.first())
        val where = if (listen.isLoopbackAddress) "" else
            ", on the network at ${reachable.joinToString { ListenAddress.hostText(it) }} (anyone there can drive these robots)"
        val lines = ArrayList<String>()
        val control = try {
            when {
                !hci -> emu.startTcp(basePort = portBase, controlPort = controlPort, listen = listen).also {
                    for (r in emu.robots) lines += "robot ${r.id} ${r.name} tcp $host:${r.tcpPort}"
                }
                h4.isNotEmpty() -> {
                    for ((r, endpoint) in emu.robots.zip(h4)) {
                        r.attachH4(parseEndpoint(endpoint))
                        lines += "robot ${r.id} ${r.name} h4 $endpoint"
                    }
                    -1
                }
                else -> {
                    val bt = VirtualBluetooth.start(robots, host = ListenAddress.hostText(listen))
                    Runtime.getRuntime().addShutdownHook(Thread { bt.close() })
                    val rfcomm = HashMap<Int, Int>()
                    for ((r, c) in emu.robots.zip(bt.controllers)) {
                        r.attachH4(c.h4)
                        val b = bt.bridge(c.address)
                        rfcomm[r.id] = b.rfcomm.port
                        lines += "robot ${r.id} ${r.name} bt ${c.address} rfcomm tcp $host:${b.rfcomm.port} l2cap tcp $host:${b.l2cap.port}"
                    }
                    emu.startControlPort(controlPort, listen) { rfcomm[it.id] ?: -1 }
                }
            }
        } catch (e: IOException) {
            emu.close()
            throw CliktError("cannot listen on ${ListenAddress.hostText(listen)}: ${e.message}")
        }
        println("PocketBot emulator: world ${w.name}, $robots robot(s), seed $seed, speed ${describe(pace)}${if (hci) ", link hci" else ""}, firmware ${emu.firmwareEngine.name.lowercase()}$where")
        lines.forEach(::println)
        if (control >= 0) println("control $host:$control")
        emu.start(pace)
        val gateway = brokerOptions?.let { options ->
            val name = gatewayName!!
            val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
            try {
                runBlocking {
                    scope.startGateway(name, options, emu.discoverer()).also { g ->
                        // The line names the robots once the gateway has announced them (a liveness guard, not a wait on time).
                        withTimeoutOrNull(ANNOUNCE_GUARD) { g.robots.first { it.size == emu.robots.size } }
                        println("gateway $name on ${options.url}: ${g.robots.value.joinToString { "$name/$it" }}")
                    }
                }
            } catch (e: BrokerException) {
                emu.close()
                throw CliktError("cannot serve the robots through ${options.url}: ${e.message}")
            } catch (e: IllegalArgumentException) {
                emu.close()
                throw UsageError(e.message ?: "bad gateway name $name", "--gateway")
            }
        }
        System.out.flush()
        fun stop() {
            // The gateway first: it tells the broker the robots are gone before their links close under it.
            gateway?.let { g -> runBlocking { withTimeoutOrNull(ANNOUNCE_GUARD) { g.close() } } }
            emu.close()
        }
        Runtime.getRuntime().addShutdownHook(Thread(::stop))
        val input = System.`in`.bufferedReader()
        while (true) {
            val line = try { input.readLine() } catch (_: Exception) { null }
            if (line == null) { Thread.sleep(Long.MAX_VALUE); continue } // no stdin (e.g. in the background): run until killed
            when (line.trim()) {
                "p" -> { emu.pause(); println("paused at ${emu.time}") }
                "r" -> { emu.resume(); println("running") }
                "s" -> { emu.pause(); emu.singleStep(); println("t=${emu.time}") }
                "t" -> println("t=${emu.time} (${emu.timeTicks} ticks of ${SimTime.TICKS_PER_SECOND} Hz)")
                "q" -> exitProcess(0) // the shutdown hook stops it
                "" -> {}
                else -> println("commands: p pause, r resume, s single step, t time, q quit")
            }
        }
    }

    private companion object {
        /** How long the gateway may take to announce the robots, or to say goodbye: a guard, not a wait. */
        val ANNOUNCE_GUARD = 5.seconds
    }

    private fun parseEndpoint(text: String): InetSocketAddress {
        val port = text.substringAfterLast(':', "").toIntOrNull()?.takeIf { it in 1..65535 }
            ?: throw UsageError("--h4 wants HOST:PORT, not $text", "--h4")
        return InetSocketAddress(text.substringBeforeLast(':').removeSurrounding("[", "]"), port)
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

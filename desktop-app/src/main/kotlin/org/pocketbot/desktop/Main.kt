package org.pocketbot.desktop

import androidx.compose.runtime.mutableStateOf
import androidx.compose.ui.unit.dp
import androidx.compose.ui.window.Window
import androidx.compose.ui.window.application
import androidx.compose.ui.window.rememberWindowState
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.flow.emptyFlow
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.desktop.model.EmulatorModel
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.desktop.ui.View
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.emulator.world.Worlds
import org.pocketbot.sdk.mqtt.BrokerException
import org.pocketbot.sdk.mqtt.BrokerOptions
import org.pocketbot.sdk.mqtt.connectBroker
import org.pocketbot.sdk.transport.BluezDiscoverer
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.EmulatorDiscoverer
import org.pocketbot.sdk.transport.SerialDiscoverer
import java.io.File
import java.net.InetSocketAddress
import kotlin.system.exitProcess
import kotlin.time.Duration.Companion.seconds

private const val USAGE = """usage: pocketbot-panel [--world NAME|FILE.json] [--robots N] [--no-emulator] [--serve [ADDRESS:]PORT] [--control-port P] [--screenshots DIR]
                       [--broker URL [--user NAME] [--password-file FILE] [--ca FILE]]
  --world W          world of the embedded emulator (default round; shipped: ${'$'}WORLDS)
  --robots N         robots in the embedded emulator (default 3); they start following the line
  --no-emulator      no embedded emulator: only robots found on this machine
  --serve A:P        put the embedded emulator's robots on the network from the start, its control port at A:P
                     (e.g. 0.0.0.0:40000, every address of this machine; A defaults to 0.0.0.0), so a phone on the
                     same Wi-Fi drives them; the World view serves and stops serving too
  --control-port P   also look for an emulator's robots on this control port (default 40000)
  --screenshots DIR  drive the panel through its main views, write a PNG of each to DIR, and exit
  --broker URL       also look for robots of other hosts through this MQTT broker (mqtts://HOST[:8883] or
                     mqtt://HOST[:1883]); each shows as GATEWAY/NAME
  --user NAME        the broker user; its password is the first line of --password-file FILE, else
                     ${'$'}POCKETBOT_BROKER_PASSWORD
  --ca FILE          the CA certificate (PEM) the broker's TLS certificate is checked against"""

/** The PocketBot control panel: an embedded emulator fleet (three robots following the round track) by default. */
fun main(args: Array<String>) {
    var world = "round"
    var robots = 3
    var embedded = true
    var controlPort = EmulatorDiscoverer.DEFAULT_CONTROL_PORT
    var serve: InetSocketAddress? = null
    var screenshots: File? = null
    var brokerUrl: String? = null
    var brokerUser: String? = null
    var passwordFile: File? = null
    var ca: File? = null
    var i = 0
    fun value(): String = args.getOrNull(++i) ?: usage("missing value for ${args[i - 1]}")
    while (i < args.size) {
        when (args[i]) {
            "--world" -> world = value()
            "--robots" -> robots = value().toIntOrNull()?.takeIf { it in 1..EmulatorModel.MAX_ROBOTS } ?: usage("--robots wants 1..${EmulatorModel.MAX_ROBOTS}")
            "--no-emulator" -> embedded = false
            "--control-port" -> controlPort = value().toIntOrNull()?.takeIf { it in 1..65535 } ?: usage("--control-port wants a TCP port")
            "--serve" -> serve = serveAddress(value()) ?: usage("--serve wants [ADDRESS:]PORT of this machine, e.g. 0.0.0.0:40000")
            "--screenshots" -> screenshots = File(value())
            "--broker" -> brokerUrl = value()
            "--user" -> brokerUser = value()
            "--password-file" -> passwordFile = File(value()).takeIf { it.canRead() } ?: usage("cannot read the password file ${args[i]}")
            "--ca" -> ca = File(value()).takeIf { it.canRead() } ?: usage("cannot read the CA certificate ${args[i]}")
            "-h", "--help" -> { println(USAGE.replace("\$WORLDS", Worlds.names.joinToString())); return }
            else -> usage("unknown argument ${args[i]}")
        }
        i++
    }
    val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
    if (serve != null && !embedded) usage("--serve serves the embedded emulator: not with --no-emulator")
    val emulator = if (embedded) {
        val at = serve ?: InetSocketAddress(ListenAddress.ANY, EmulatorDiscoverer.DEFAULT_CONTROL_PORT)
        try { EmulatorModel(scope, world, robots, serveAt = at) } catch (e: IllegalArgumentException) { usage("cannot load world $world: ${e.message}") }
    } else null
    if (brokerUrl == null && (brokerUser != null || passwordFile != null || ca != null)) usage("--user, --password-file and --ca need --broker")
    val broker = brokerUrl?.let { url ->
        val options = try {
            BrokerOptions(url) {
                username = brokerUser
                passwordFrom(passwordFile)
                trustedCertificates = ca
            }
        } catch (e: IllegalArgumentException) {
            usage("--broker wants mqtt://HOST[:PORT] or mqtts://HOST[:PORT]: ${e.message}")
        }
        try {
            runBlocking { scope.connectBroker(options) }
        } catch (e: BrokerException) {
            System.err.println("pocketbot-panel: cannot use the broker $url: ${e.message}")
            emulator?.close()
            exitProcess(1)
        }
    }
    val sources = discoverersOnThisMachine(controlPort, emulator) + listOfNotNull(broker?.let { "broker ${it.options.url}" to it.discoverer() })
    val model = PanelModel(scope, sources, emulator)
    fun close() {
        model.close()
        broker?.let { runBlocking { withTimeoutOrNull(3.seconds) { it.close() } } }
    }
    if (emulator != null && serve != null) {
        try {
            emulator.serve()
        } catch (e: java.io.IOException) {
            System.err.println("pocketbot-panel: cannot serve the embedded emulator at ${ListenAddress.hostText(serve.address)}:${serve.port}: ${e.message}")
            close()
            exitProcess(1)
        }
        println("pocketbot-panel: the embedded emulator is on the network; type its control port into the phone: ${emulator.serving.value?.addresses?.joinToString()}")
    }
    if (emulator != null) scope.launch { startFleet(model) }
    val view = mutableStateOf(View.OVERVIEW)
    application {
        Window(onCloseRequest = { close(); exitApplication() }, title = "PocketBot panel",
            state = rememberWindowState(width = 1440.dp, height = 900.dp)) {
            PanelApp(model, view)
            screenshots?.let { dir -> Screenshots(window, model, view, dir) { close(); exitApplication() } }
        }
    }
}

/**
 * Every other place a robot can be found from this machine: an emulator's control port, Bluetooth, serial ports. The
 * control port is not asked while the panel's own [emulator] serves on it: its robots are found in process already.
 */
fun discoverersOnThisMachine(controlPort: Int, emulator: EmulatorModel? = null): Map<String, Discoverer> = mapOf(
    "emulator (control port $controlPort)" to object : Discoverer {
        private val other = EmulatorDiscoverer(controlPort = controlPort)
        override fun discover() = if (emulator?.serving?.value?.controlPort == controlPort) emptyFlow() else other.discover()
    },
    "Bluetooth" to BluezDiscoverer(),
    "serial" to SerialDiscoverer(),
)

/** `ADDRESS:PORT`, `[v6]:PORT` or `PORT` (on every address) as a place to listen, or null when it is none. */
fun serveAddress(text: String): InetSocketAddress? {
    val port = text.substringAfterLast(':').toIntOrNull()?.takeIf { it in 1..65535 } ?: return null
    val host = if (':' in text) text.substringBeforeLast(':') else return InetSocketAddress(ListenAddress.ANY, port)
    return try { InetSocketAddress(ListenAddress.parse(host), port) } catch (e: IllegalArgumentException) { null }
}

/** Connects the embedded robots (their odometry on their true start pose) and starts them following the line. */
suspend fun startFleet(model: PanelModel, speedsMps: List<Double> = listOf(0.15)) {
    val robots = model.connectEmbedded()
    robots.forEachIndexed { i, r ->
        r.startLineFollowing(speedsMps[i % speedsMps.size], org.pocketbot.sdk.ColourMode.PLAIN)
    }
}

private fun usage(message: String): Nothing {
    System.err.println("pocketbot-panel: $message")
    System.err.println(USAGE.replace("\$WORLDS", Worlds.names.joinToString()))
    exitProcess(2)
}

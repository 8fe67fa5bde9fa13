package org.pocketbot.cli

import java.util.concurrent.ConcurrentLinkedQueue
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.async
import kotlinx.coroutines.awaitAll
import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.flow.collect
import kotlinx.coroutines.flow.takeWhile
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.mqtt.BrokerClient
import org.pocketbot.sdk.mqtt.BrokerException
import org.pocketbot.sdk.mqtt.BrokerOptions
import org.pocketbot.sdk.mqtt.BrokerRobotDevice
import org.pocketbot.sdk.transport.BluezDiscoverer
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.EmulatorDiscoverer
import org.pocketbot.sdk.transport.MergedDiscoverer
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.SerialDiscoverer
import org.pocketbot.sdk.transport.RobotAddress
import java.nio.file.Files
import java.nio.file.Paths
import kotlin.time.Duration

/** No robot answers to the name, id or address the user gave: exit code 3. */
class NoSuchRobotException(message: String) : Exception(message)

/** The robot's link went down while a command was watching it: exit code 5. */
class LinkLostException(message: String) : Exception(message)

/** A robot found by a source, and which source. */
class Found(val device: RobotDevice, val source: String) {
    /** The name a user types for it: a robot behind a broker's gateway is GATEWAY/ROBOT, any other its own name. */
    val name: String get() = (device as? BrokerRobotDevice)?.let { "${it.gateway}/${it.robot}" } ?: device.name

    /** True when [text] names this robot: by [name], its own name or its address. */
    fun answersTo(text: String) = text == name || text == device.name || text == device.address
}

/** Where to look for robots, as the global options say: [broker] adds the robots of every gateway behind it. */
class Sources(
    val host: String, private val controlPort: Int, val kinds: Set<String>, private val timeout: Duration,
    val broker: BrokerOptions? = null,
) {
    private fun discoverers(broker: BrokerClient?): Map<String, Discoverer> = buildMap {
        if ("emulator" in kinds) put("emulator", EmulatorDiscoverer(host, controlPort))
        if ("serial" in kinds) put("serial", SerialDiscoverer())
        if ("bluetooth" in kinds) put("bluetooth", BluezDiscoverer(duration = timeout))
        if (broker != null) put("broker", broker.discoverer())
    }

    /** These sources with the robots behind [broker] too. */
    fun through(broker: BrokerOptions) = Sources(host, controlPort, kinds, timeout, broker)

    /**
     * Every robot the sources find within the timeout (through [broker] too, connected to [Sources.broker]), or as soon
     * as [enough] says the robots found so far will do; sources that cannot search are reported to [problem].
     */
    suspend fun scan(broker: BrokerClient?, problem: (String) -> Unit = {}, enough: (List<Found>) -> Boolean = { false }): List<Found> {
        val found = java.util.Collections.synchronizedList(mutableListOf<Found>())
        val tagged = discoverers(broker).mapValues { (name, d) ->
            object : Discoverer {
                override fun discover() = kotlinx.coroutines.flow.flow { d.discover().collect { found += Found(it, name); emit(it) } }
            }
        }
        withTimeoutOrNull(timeout) {
            MergedDiscoverer(tagged) { source, e -> problem("$source: ${e.message ?: e}") }.discover()
                .takeWhile { !enough(found.toList()) }.collect()
        }
        return found.toList().distinctBy { it.device.address }
    }
}

/**
 * The robot at [address] when it is one a person can type without a scan: `tcp://HOST:PORT` (an emulated robot, a
 * serial-to-TCP bridge) or `serial:PATH` (see [RobotAddress]); null for anything else (a name, an id).
 *
 * @throws IllegalArgumentException for an address of those kinds that is not right (no port, say): what is wrong.
 */
fun deviceAt(address: String): RobotDevice? = if (RobotAddress.isAddress(address)) RobotAddress.parse(address) else null

/**
 * Finds the robots [names] (each a name, an address, or a numeric id) among [found] and connects them, or every
 * robot found with [all]. A name or address picks its device without connecting the others (an address that can be
 * typed, see [deviceAt], needs no scan); an id needs each candidate's hello, so the candidates are connected and those
 * that are not wanted are closed again. A robot GATEWAY/ROBOT that is not found on [broker] fails saying why when its
 * gateway does. When it fails, it closes what it connected: the robots belong to this scope, which would wait for them.
 */
suspend fun CoroutineScope.connectRobots(
    found: List<Found>, names: List<String>, all: Boolean, options: RobotOptions, progress: Progress, broker: BrokerClient? = null,
): List<Robot> {
    val connected = ConcurrentLinkedQueue<Robot>()
    try {
        if (all) {
            if (found.isEmpty()) throw NoSuchRobotException("no robots found")
            return connectAll(found.map { it.device }, options, progress, connected)
        }
        return names.map { name ->
            val direct = found.firstOrNull { it.answersTo(name) }?.device ?: deviceAt(name)
            when {
                direct != null -> connectAll(listOf(direct), options, progress, connected).single()
                name.toIntOrNull() != null -> {
                    val robots = connectAll(found.map { it.device }, options, progress, connected)
                    val wanted = robots.firstOrNull { it.identity.robotId == name.toInt() }
                    robots.filter { it !== wanted }.forEach { it.disconnect() }
                    wanted ?: throw NoSuchRobotException("no robot with id $name among ${found.size} found")
                }
                else -> {
                    broker?.let { gatewayTrouble(it, name) }
                    throw NoSuchRobotException("no robot '$name' (found: ${found.joinToString { it.name }.ifEmpty { "none" }})")
                }
            }
        }
    } catch (e: Throwable) {
        connected.forEach { it.close() }
        throw e
    }
}

/**
 * Fails saying why the robot [name] (GATEWAY/ROBOT) is not on [broker] when its gateway explains it: offline (exit 1,
 * like every broker failure) or unknown to the broker (exit 3).
 */
private fun gatewayTrouble(broker: BrokerClient, name: String) {
    val gateway = name.substringBefore('/', missingDelimiterValue = "").ifEmpty { return }
    val gateways = broker.gateways.value
    val presence = gateways[gateway]
        ?: throw NoSuchRobotException("no gateway '$gateway' on ${broker.options.url} (gateways: " +
            gateways.entries.sortedBy { it.key }.joinToString { (n, p) -> if (p.online) n else "$n (offline)" }.ifEmpty { "none" } + ")")
    if (!presence.online) throw BrokerException("gateway '$gateway' is offline: its robots cannot be reached through ${broker.options.url}")
}

/**
 * Connects [devices] at once, adding each to [connected]. Each robot belongs to this scope (the command's); a connect
 * that fails ends the others and surfaces as its own exception (inside a child scope, so it does not cancel the
 * command's scope instead).
 */
private suspend fun CoroutineScope.connectAll(devices: List<RobotDevice>, options: RobotOptions, progress: Progress, connected: MutableCollection<Robot>): List<Robot> {
    val owner = this
    var done = 0
    progress.show("connecting 0/${devices.size}")
    return coroutineScope {
        devices.map { d ->
            async { d.connect(owner, options).also { connected += it; progress.show("connecting ${++done}/${devices.size}") } }
        }.awaitAll()
    }.also { progress.clear() }
}

/** A progress line on stderr, only when stderr is a terminal (a script's log gets none of it). */
class Progress(private val enabled: Boolean = stderrIsTerminal()) {
    fun show(text: String) { if (enabled) System.err.print("\r\u001b[K$text") }
    fun clear() { if (enabled) System.err.print("\r\u001b[K") }

    companion object {
        fun stderrIsTerminal(): Boolean = try {
            Files.readSymbolicLink(Paths.get("/proc/self/fd/2")).toString().let { it.startsWith("/dev/pts/") || it.startsWith("/dev/tty") }
        } catch (_: Exception) {
            false
        }
    }
}

/**
 * The robot as the user names it: GATEWAY/ROBOT behind a broker's gateway (its address ends with them, so two
 * gateways' PocketBot-1 differ), else the name it advertises.
 */
val Robot.label: String
    get() = identity.address.takeIf { it.startsWith("mqtt://") || it.startsWith("mqtts://") }
        ?.substringAfter("://")?.substringAfter('/', "")?.takeIf { path -> path.count { it == '/' } == 1 }
        ?: identity.name

package org.pocketbot.cli

import com.github.ajalt.clikt.core.Context
import com.github.ajalt.clikt.core.CoreCliktCommand
import com.github.ajalt.clikt.core.ProgramResult
import com.github.ajalt.clikt.core.UsageError
import com.github.ajalt.clikt.core.requireObject
import com.github.ajalt.clikt.parameters.arguments.argument
import com.github.ajalt.clikt.parameters.arguments.multiple
import com.github.ajalt.clikt.parameters.groups.provideDelegate
import com.github.ajalt.clikt.parameters.options.option
import com.github.ajalt.clikt.parameters.options.required
import com.github.ajalt.clikt.parameters.types.int
import com.github.ajalt.clikt.parameters.types.restrictTo
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.awaitCancellation
import kotlinx.coroutines.flow.emitAll
import kotlinx.coroutines.flow.flow
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.sdk.mqtt.BrokerException
import org.pocketbot.sdk.mqtt.Gateway
import org.pocketbot.sdk.mqtt.GatewayStats
import org.pocketbot.sdk.mqtt.startGateway
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.EmulatorDiscoverer
import org.pocketbot.sdk.transport.RobotDevice
import kotlin.time.Duration.Companion.seconds

/**
 * `pocketbot gateway`: serves the robots this host reaches (by address, or an emulator's control port) to an MQTT
 * broker until interrupted, then says what it did (its counters).
 */
class GatewayCommand : CoreCliktCommand(name = "gateway") {
    override fun help(context: Context) = """
        Serves the robots this host reaches to an MQTT broker, under the gateway's name, until stopped (Ctrl-C):
        programs on other hosts then find and drive them there as NAME/ROBOT (pocketbot --broker URL ...). The
        robots are given by address (tcp://HOST:PORT, serial:PATH) and/or an emulator's control port. It prints each
        robot it serves, and its counters when it stops.

        Example: pocketbot gateway --broker mqtts://central:8883 --ca ca.crt --user lab1 --password-file lab1.pw --name lab1 serial:/dev/rfcomm0
    """.trimIndent()

    private val globals by requireObject<Globals>()
    private val name by option("--name", help = "the gateway's name: its robots' topics are pb/v1/NAME/... (the broker's ACL grants them to its user)").required()
    private val emulatorPort by option("--emulator-port", metavar = "PORT", help = "also serve every robot of the emulator whose control port this is (on --host)")
        .int().restrictTo(1..65535)
    private val broker by brokerOptions()
    private val addresses by argument("ADDRESS", help = "a robot's address: tcp://HOST:PORT or serial:PATH").multiple()

    override fun run() {
        val options = globals.with(broker).sources.broker ?: throw UsageError("a gateway needs --broker URL", "--broker")
        if (addresses.isEmpty() && emulatorPort == null) throw UsageError("name the robots to serve: ADDRESS... or --emulator-port")
        val devices = addresses.map { a ->
            try { deviceAt(a) } catch (e: IllegalArgumentException) { throw UsageError(e.message ?: a) }
                ?: throw UsageError("$a is no address: tcp://HOST:PORT or serial:PATH")
        }
        val robots = object : Discoverer {
            override fun discover() = flow<RobotDevice> {
                devices.forEach { emit(it) }
                emulatorPort?.let { emitAll(EmulatorDiscoverer(globals.sources.host, it).discover()) }
            }
        }
        // On the shared pool, not this thread's loop: the shutdown hook closes the gateway while this thread waits.
        runBlocking(Dispatchers.Default) {
            val gateway = try {
                startGateway(name, options, robots)
            } catch (e: BrokerException) {
                System.err.println("pocketbot: cannot serve through ${options.url}: ${e.message}")
                throw ProgramResult(Exit.FAILED)
            } catch (e: IllegalArgumentException) {
                throw UsageError(e.message ?: "bad gateway name $name", "--name")
            }
            val told = mutableSetOf<String>()
            launch {
                gateway.robots.collect { served ->
                    for (r in served - told) println("serving $name/$r")
                    told += served
                    System.out.flush()
                }
            }
            println("gateway $name on ${options.url}")
            System.out.flush()
            // Interrupted (Ctrl-C, kill): the hook says goodbye to the broker (the robots gone, the gateway offline) and
            // prints the counters; this coroutine is never resumed.
            Runtime.getRuntime().addShutdownHook(Thread { stop(gateway) })
            awaitCancellation()
        }
    }

    private fun stop(gateway: Gateway) {
        runBlocking { withTimeoutOrNull(GOODBYE_GUARD) { gateway.close() } }
        println("gateway $name stopped: ${counters(gateway.stats.value)}")
        System.out.flush()
    }

    private companion object {
        /** How long the goodbye may take on a broker that is gone: a guard, not a wait. */
        val GOODBYE_GUARD = 5.seconds
    }
}

/** The gateway's counters in one line, `name=value` each, for people and for grep. */
fun counters(s: GatewayStats): String = with(s) {
    "sessions=$sessions frames_up=$framesUp messages_up=$messagesUp frames_down=$framesDown dropped_garbage=$droppedGarbage " +
        "dropped_oversize=$droppedOversize dropped_unknown_robot=$droppedUnknownRobot dropped_late=$droppedLate dropped_not_allowed=$droppedNotAllowed"
}

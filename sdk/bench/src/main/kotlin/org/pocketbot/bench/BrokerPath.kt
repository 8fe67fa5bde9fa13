package org.pocketbot.bench

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.flow.asFlow
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.sdk.mqtt.BrokerClient
import org.pocketbot.sdk.mqtt.BrokerRobotDevice
import org.pocketbot.sdk.mqtt.Gateway
import org.pocketbot.sdk.mqtt.connectBroker
import org.pocketbot.sdk.mqtt.faults.startRoomBroker
import org.pocketbot.sdk.mqtt.startGateway
import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.RobotDevice
import java.io.File
import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds

/**
 * Robots reached through Mosquitto as users run it (the shipped configuration, TLS, passwords, ACL): a gateway `lab1`
 * serves [robots] to a broker (or, [bridged], to a room broker bridged by the shipped bridge.conf to the central
 * broker), and a fleet client `alice` on the central broker reaches them as [devices], in the same order.
 */
internal class BrokerPath private constructor(
    private val brokers: List<MosquittoBroker>,
    private val scope: CoroutineScope,
    private val gateway: Gateway,
    private val client: BrokerClient,
    val devices: List<RobotDevice>,
) : AutoCloseable {
    /** What the broker carried while measured: its CPU (in cores), and the gateway's up messages and frames a second. */
    class Load(val brokerCores: Double, val messagesPerS: Double, val framesPerS: Double)

    private var from: Triple<Long, Long, GatewayCounters>? = null

    private class GatewayCounters(val messages: Long, val frames: Long)

    /** Starts the measured interval. */
    fun measureFrom() {
        from = Triple(System.nanoTime(), brokerCpuNanos(), counters())
    }

    /** The load since [measureFrom]. */
    fun measured(): Load {
        val (t0, cpu0, c0) = checkNotNull(from)
        val seconds = (System.nanoTime() - t0) / 1e9
        val c = counters()
        return Load((brokerCpuNanos() - cpu0) / 1e9 / seconds, (c.messages - c0.messages) / seconds, (c.frames - c0.frames) / seconds)
    }

    private fun counters() = gateway.stats.value.let { GatewayCounters(it.messagesUp, it.framesUp) }

    /** CPU time of every broker process so far (Linux `/proc/<pid>/stat`: utime + stime in clock ticks of 10 ms). */
    private fun brokerCpuNanos(): Long = brokers.sumOf { b ->
        val fields = File("/proc/${b.pid}/stat").readText().substringAfterLast(')').trim().split(' ')
        (fields[11].toLong() + fields[12].toLong()) * 10_000_000L
    }

    override fun close() {
        runBlocking {
            client.close()
            gateway.close()
        }
        scope.cancel()
        brokers.asReversed().forEach { it.close() }
    }

    companion object {
        /** How long [start] waits for the client to see every robot. */
        private val SEEN: Duration = 30.seconds

        /**
         * Starts the broker (or the bridged pair), the gateway serving [robots] (upBatchWindow 10 ms when [batched],
         * else 0) and the client, and waits until the client sees every robot.
         */
        suspend fun start(robots: List<RobotDevice>, batched: Boolean = true, bridged: Boolean = false): BrokerPath {
            val central = MosquittoBroker.start()
            val brokers = mutableListOf(central)
            val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
            try {
                val room = if (bridged) startRoomBroker(central).also { brokers += it } else central
                val gateway = scope.startGateway("lab1", room.options("lab1") { if (!batched) upBatchWindow = Duration.ZERO }, DevicesOf(robots))
                val client = scope.connectBroker(central.options("alice"))
                val ids = withTimeout(SEEN) { gateway.robots.first { it.size == robots.size } }
                val seen = withTimeout(SEEN) {
                    var found: Map<String, RobotDevice>
                    do {
                        found = client.discoverer().discover().toList().associateBy { (it as BrokerRobotDevice).robot }
                    } while (!found.keys.containsAll(ids))
                    found
                }
                return BrokerPath(brokers, scope, gateway, client, ids.map { seen.getValue(it) })
            } catch (e: Throwable) {
                scope.cancel()
                brokers.asReversed().forEach { it.close() }
                throw e
            }
        }
    }

    private class DevicesOf(private val robots: List<RobotDevice>) : Discoverer {
        override fun discover() = robots.asFlow()
    }
}

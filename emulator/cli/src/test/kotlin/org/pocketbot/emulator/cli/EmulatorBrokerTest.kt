package org.pocketbot.emulator.cli

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.mqtt.BrokerRobotDevice
import org.pocketbot.sdk.mqtt.connectBroker
import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import java.io.File
import java.util.concurrent.LinkedBlockingQueue
import java.util.concurrent.TimeUnit
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.test.fail
import kotlin.time.Duration.Companion.seconds

/**
 * `make emulator ARGS="--broker URL --gateway NAME ..."` as a process of its own publishes its robots through a real
 * Mosquitto run with the shipped configuration; a program on another host (here a BrokerClient) finds and drives one.
 */
class EmulatorBrokerTest {
    @Test
    fun `the emulator's robots are served through a broker under the gateway's name until it stops`() {
        val guard = 60.seconds
        MosquittoBroker.start().use { broker ->
            val password = File.createTempFile("lab1", ".pw").apply { deleteOnExit(); writeText(broker.password("lab1")) }
            val java = File(System.getProperty("java.home"), "bin/java").path
            val process = ProcessBuilder(java, "-XX:-DontCompileHugeMethods", "-cp", System.getProperty("java.class.path"),
                "org.pocketbot.emulator.cli.MainKt", "--robots", "2", "--world", "straight", "--port-base", "0", "--control-port", "-1",
                "--broker", broker.url, "--ca", broker.caFile.path, "--user", "lab1", "--password-file", password.path, "--gateway", "lab1")
                .redirectErrorStream(true).start()
            val lines = LinkedBlockingQueue<String>()
            val output = StringBuffer()
            Thread { process.inputStream.bufferedReader().forEachLine { output.append(it).append('\n'); lines.put(it) } }.apply { isDaemon = true }.start()
            val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
            try {
                val announced = generateSequence { lines.poll(guard.inWholeSeconds, TimeUnit.SECONDS) ?: fail("no gateway line: $output") }
                    .first { it.startsWith("gateway ") }
                assertEquals("gateway lab1 on ${broker.url}: lab1/PocketBot-1, lab1/PocketBot-2", announced, "$output")

                runBlocking {
                    val client = scope.connectBroker(broker.options("alice"))
                    val devices = withTimeout(guard) { client.discoverer().discover().toList() }.map { it as BrokerRobotDevice }
                    assertEquals(listOf("lab1/PocketBot-1", "lab1/PocketBot-2"), devices.map { "${it.gateway}/${it.robot}" }.sorted())
                    val robot = devices.first { it.robot == "PocketBot-2" }.connect(scope, RobotOptions { settingsCache = InMemorySettingsCache() })
                    assertEquals("PocketBot-2", robot.identity.name)
                    val result = robot.locomotion.enqueue(Movement.Straight(0.05, speedMps = 0.1)).await()
                    assertEquals(MovementOutcome.FINISHED, result.outcome, "$result")
                    assertTrue(kotlin.math.abs(result.done!! - 0.05) < 0.005, "$result")
                    robot.disconnect()

                    // Stopped, the gateway tells the broker first: its robots are gone and it is offline.
                    process.destroy()
                    assertTrue(process.waitFor(guard.inWholeSeconds, TimeUnit.SECONDS), "the emulator did not stop: $output")
                    withTimeout(guard) { client.gateways.first { it["lab1"]?.online == false } }
                    assertEquals(emptyList(), withTimeout(guard) { client.discoverer().discover().toList() })
                    client.close()
                }
            } finally {
                scope.cancel()
                if (process.isAlive) process.destroyForcibly().waitFor()
            }
        }
    }
}

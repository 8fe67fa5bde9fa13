package org.pocketbot.cli

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import kotlinx.serialization.json.jsonPrimitive
import org.junit.jupiter.api.AfterAll
import org.junit.jupiter.api.BeforeAll
import org.junit.jupiter.api.Test
import org.junit.jupiter.api.TestInstance
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.sdk.mqtt.Gateway
import org.pocketbot.sdk.mqtt.connectBroker
import org.pocketbot.sdk.mqtt.startGateway
import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import java.io.File
import kotlin.math.hypot
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds

/**
 * `pocketbot` as a process on a host without robots: it finds and drives an emulated robot (the real firmware) of
 * another host through a real Mosquitto run with the project's shipped configuration (TLS, passwords, ACL), behind
 * a gateway; and `pocketbot gateway` serving an emulator's robots to that broker. Ground truth from the emulator.
 */
@TestInstance(TestInstance.Lifecycle.PER_CLASS)
class CliBrokerTest {
    private lateinit var broker: MosquittoBroker
    private lateinit var emulator: Emulator
    private lateinit var gateway: Gateway
    private val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
    private val dir = kotlin.io.path.createTempDirectory("pocketbot-cli-broker").toFile()

    @BeforeAll
    fun start() {
        broker = MosquittoBroker.start()
        emulator = Emulator.local(robots = 1, world = "round")
        emulator.start(Speed.Realtime(1.0))
        gateway = runBlocking { scope.startGateway("lab1", broker.options("lab1"), emulator.discoverer()) }
        runBlocking { withTimeout(GUARD_SECONDS.seconds) { gateway.robots.first { it.isNotEmpty() } } }
    }

    @AfterAll
    fun stop() {
        runBlocking { gateway.close() }
        scope.cancel()
        emulator.close()
        broker.close()
        dir.deleteRecursively()
    }

    /** A file holding [user]'s password, as `--password-file` reads it. */
    private fun passwordFile(user: String, password: String = broker.password(user)) =
        File(dir, "$user.pw").apply { writeText(password + "\n") }

    /** `pocketbot` as [user] through the broker (TLS, the test CA), looking nowhere else. */
    private fun pocketbot(user: String, vararg args: String): Run = runPocketBot(
        listOf("--broker", broker.url, "--ca", broker.caFile.path, "--user", user, "--password-file", passwordFile(user).path,
            "--sources", "broker", "--scan-seconds", "3") + args,
    )

    @Test
    fun aRobotOfAnotherHostIsListedMovedAndReadThroughTheBrokerAsGatewaySlashName() {
        val scan = pocketbot("alice", "scan", "--json")
        assertEquals(0, scan.code, "$scan")
        val row = jsonLines(scan.out).single()
        assertEquals("lab1/PocketBot-1", row["name"]!!.jsonPrimitive.content, "$scan")
        assertEquals("broker", row["source"]!!.jsonPrimitive.content)
        assertTrue(row["address"]!!.jsonPrimitive.content.startsWith("mqtt://127.0.0.1:${broker.tlsPort}/lab1/"), "$scan")

        val sim = emulator.robot(1)
        val start = sim.truePose
        val move = pocketbot("alice", "move", "lab1/PocketBot-1", "straight", "0.05", "--speed", "0.1", "--wait", "--json")
        assertEquals(0, move.code, "$move")
        assertEquals("finished", jsonLines(move.out).single()["outcome"]!!.jsonPrimitive.content, "$move")
        val moved = hypot(sim.truePose.xM - start.xM, sim.truePose.yM - start.yM)
        assertTrue(moved in 0.045..0.055, "the robot really moved ${moved * 1000} mm of 50")

        // The broker's options after the command, as after `--json`.
        val state = runPocketBot(listOf("--sources", "broker", "state", "lab1/PocketBot-1", "--json", "--fields", "pose,time.time_ms",
            "--broker", broker.url, "--ca", broker.caFile.path, "--user", "alice", "--password-file", passwordFile("alice").path))
        assertEquals(0, state.code, "$state")
        val s = jsonLines(state.out).single()
        assertEquals("lab1/PocketBot-1", s["robot"]!!.jsonPrimitive.content, "named as the user names it")
        assertTrue(s["time.time_ms"]!!.jsonPrimitive.content.toLong() > 0, "$state")
        assertTrue(gateway.stats.value.sessions >= 2, "move and state each had a session of their own: ${gateway.stats.value}")
    }

    @Test
    fun refusedCredentialsAnUnknownRobotAndBadOptionsSayWhy() {
        // The password from the environment, as a script gives it: a wrong one is refused by the broker, and said so.
        val wrong = runPocketBot(listOf("--broker", broker.url, "--ca", broker.caFile.path, "--user", "alice", "--sources", "broker", "scan"),
            env = mapOf("POCKETBOT_BROKER_PASSWORD" to "not-alices-password"))
        assertEquals(Exit.FAILED, wrong.code, "$wrong")
        assertTrue(Regex("not authori[sz]ed|bad user ?name or password", RegexOption.IGNORE_CASE).containsMatchIn(wrong.err), "$wrong")
        assertTrue("Exception" !in wrong.err, "a stack trace instead of a reason: $wrong")

        val unknownGateway = pocketbot("alice", "info", "lab9/PocketBot-1")
        assertEquals(Exit.NO_SUCH_ROBOT, unknownGateway.code, "$unknownGateway")
        assertTrue("no gateway 'lab9'" in unknownGateway.err && "lab1" in unknownGateway.err, "$unknownGateway")

        val noBroker = runPocketBot(listOf("--user", "alice", "scan"))
        assertEquals(Exit.USAGE, noBroker.code, "$noBroker")
        assertTrue("need --broker" in noBroker.err, "$noBroker")
        val brokerSourceWithoutBroker = runPocketBot(listOf("--sources", "broker", "state", "lab1/PocketBot-1"))
        assertEquals(Exit.USAGE, brokerSourceWithoutBroker.code, "$brokerSourceWithoutBroker")
        assertTrue("--sources broker needs --broker URL" in brokerSourceWithoutBroker.err, "$brokerSourceWithoutBroker")
        val badUrl = runPocketBot(listOf("--broker", "http://127.0.0.1:1", "scan"))
        assertEquals(Exit.USAGE, badUrl.code, "$badUrl")
        assertTrue("mqtt://" in badUrl.err, "$badUrl")
        val gatewayWithoutRobots = runPocketBot(listOf("gateway", "--broker", broker.url, "--name", "lab2"))
        assertEquals(Exit.USAGE, gatewayWithoutRobots.code, "$gatewayWithoutRobots")
    }

    @Test
    fun pocketbotGatewayServesAnEmulatorsRobotsUntilInterruptedThenItsRobotsAreOffline() {
        val controlPort = emulator.startTcp(basePort = 0, controlPort = 0)
        val served = PocketBotProcess(listOf("--host", "127.0.0.1", "gateway", "--broker", broker.url, "--ca", broker.caFile.path,
            "--user", "lab2", "--password-file", passwordFile("lab2").path, "--name", "lab2", "--emulator-port", "$controlPort"))
        try {
            served.awaitLine(Regex("""^gateway lab2 on ${Regex.escape(broker.url)}$"""))
            served.awaitLine(Regex("""^serving lab2/PocketBot-1$"""))
            // A program elsewhere sees the robot behind the new gateway, and drives it (over the emulator's TCP port).
            runBlocking {
                val client = scope.connectBroker(broker.options("alice"))
                try {
                    withTimeout(GUARD_SECONDS.seconds) { client.gateways.first { it["lab2"]?.online == true } }
                } finally {
                    client.close()
                }
            }
            val sim = emulator.robot(1)
            val heading = sim.truePose.headingRad
            val rotate = pocketbot("alice", "move", "lab2/PocketBot-1", "rotate", "30", "--speed", "0.1", "--wait")
            assertEquals(0, rotate.code, "$rotate")
            val turned = Math.toDegrees(Math.IEEEremainder(sim.truePose.headingRad - heading, 2 * Math.PI))
            assertTrue(kotlin.math.abs(turned - 30) < 10, "turned $turned degrees for 30")

            val stopped = served.interrupt()
            val counters = Regex("""^gateway lab2 stopped: sessions=(\d+) frames_up=(\d+) .*frames_down=(\d+) """, RegexOption.MULTILINE)
                .find(stopped.out) ?: throw AssertionError("no counters when interrupted: $stopped")
            assertTrue(counters.groupValues[1].toInt() >= 1 && counters.groupValues[3].toLong() > 0, "$stopped")

            val offline = pocketbot("alice", "move", "lab2/PocketBot-1", "straight", "0.01")
            assertEquals(Exit.FAILED, offline.code, "$offline")
            assertTrue("gateway 'lab2' is offline" in offline.err, "$offline")
        } finally {
            served.kill()
        }
    }
}

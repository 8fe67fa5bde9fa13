package org.pocketbot.sdk.mqtt

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.async
import kotlinx.coroutines.cancel
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.junit.jupiter.api.AfterAll
import org.junit.jupiter.api.BeforeAll
import org.junit.jupiter.api.Test
import org.junit.jupiter.api.TestInstance
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.NotDriverException
import org.pocketbot.sdk.Role
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import org.pocketbot.sdk.transport.Transport
import org.pocketbot.sdk.transport.TransportLostException
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * The fleet across hosts, end to end: a real Mosquitto with the shipped configuration, two gateways (lab1, lab2)
 * each serving an in-process emulator's robot in real time, and fleet clients that find and drive them through the
 * broker with the SDK's default options. Ground truth comes from the emulators.
 */
@TestInstance(TestInstance.Lifecycle.PER_CLASS)
class MqttFleetTest {
    private lateinit var broker: MosquittoBroker
    private val emulators = List(2) { Emulator.local(robots = 1, world = "straight") }
    private val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
    private lateinit var gateways: List<Gateway>

    @BeforeAll
    fun start() = runBlocking<Unit> {
        broker = MosquittoBroker.start()
        emulators.forEach { it.start(Speed.Realtime(1.0)) }
        gateways = listOf("lab1", "lab2").mapIndexed { i, name ->
            scope.startGateway(name, broker.options(name), emulators[i].discoverer())
        }
        gateways.forEach { g -> withTimeout(5.seconds) { g.robots.first { it.size == 1 } } }
    }

    @AfterAll
    fun stop() = runBlocking<Unit> {
        gateways.forEach { it.close() }
        scope.cancel()
        emulators.forEach { it.close() }
        broker.close()
    }

    @Test
    fun aClientDrivesARobotOfEachGatewayAndAWatcherSeesWhoDrives() = runBlocking<Unit> {
        val alice = connectBroker(broker.options("alice"))
        val devices = alice.discoverer().discover().toList().map { it as BrokerRobotDevice }
        assertEquals(setOf("lab1", "lab2"), devices.map { it.gateway }.toSet(), "$devices")
        assertEquals(setOf("PocketBot-1"), devices.map { it.name }.toSet())
        assertEquals(setOf(true), alice.gateways.value.values.map { it.online }.toSet(), "${alice.gateways.value}")

        val robots = devices.map { it.connect(this) }
        val truths = devices.map { d -> emulators[if (d.gateway == "lab1") 0 else 1].robots.single() }
        val before = truths.map { it.trueWheelDistances }
        val moves = robots.map { r -> async { r.locomotion.enqueue(Movement.Straight(0.2, 0.2)).await() } }

        // Meanwhile bob, who may only watch, watches lab1's robot and is told alice drives it.
        val bob = connectBroker(broker.options("bob") { watchOnly = true })
        val lab1Robot = devices.first { it.gateway == "lab1" }.robot
        val watched = bob.device("lab1", lab1Robot).connect(this, RobotOptions { role = Role.WATCH })
        withTimeout(5.seconds) { bob.leases.first { it["lab1" to lab1Robot] == "alice" } }

        val results = moves.map { it.await() }
        for ((i, result) in results.withIndex()) {
            assertEquals(MovementOutcome.FINISHED, result.outcome, "$result")
            val after = truths[i].trueWheelDistances
            val truth = (after.leftM - before[i].leftM + after.rightM - before[i].rightM) / 2
            assertEquals(0.2, truth, 0.01, "robot of ${devices[i].gateway}: ground truth")
            assertEquals(truth, result.done!!, 0.005, "robot of ${devices[i].gateway}: what the SDK says was done")
        }
        assertTrue(gateways.all { it.stats.value.dropped == 0L }, "${gateways.map { it.stats.value }}")
        watched.disconnect()
        robots.forEach { it.disconnect() }
        bob.close()
        alice.close()
    }

    @Test
    fun oneClientDrivesARobotAtATimeUntilAnotherTakesItOver() = runBlocking<Unit> {
        // Two programs of one driver user, each with its own broker connection and the SDK's default role (drive).
        val first = connectBroker(broker.options("alice"))
        val second = connectBroker(broker.options("alice"))
        val lab1Robot = gateways[0].robots.value.single()
        val truth = emulators[0].robots.single()
        val driving = first.device("lab1", lab1Robot).connect(this)
        val other = second.device("lab1", lab1Robot).connect(this)

        // The robot keeps its driver: the second program's movement is refused, and the robot does not move.
        val before = truth.trueWheelDistances
        assertFailsWith<NotDriverException> { other.locomotion.enqueue(Movement.Straight(0.05, 0.2)).await() }
        delay(300.milliseconds)
        fun driven() = truth.trueWheelDistances.let { (it.leftM - before.leftM + it.rightM - before.rightM) / 2 }
        assertEquals(0.0, driven(), 0.0005, "the refused movement moved the robot")

        // Taking it over moves the drive: now the first program is refused, and the second one's movement runs once.
        other.takeOver()
        assertFailsWith<NotDriverException> { driving.locomotion.enqueue(Movement.Straight(0.05, 0.2)).await() }
        val result = other.locomotion.enqueue(Movement.Straight(0.05, 0.2)).await()
        assertEquals(MovementOutcome.FINISHED, result.outcome, "$result")
        delay(300.milliseconds)
        assertEquals(0.05, driven(), 0.003, "ground truth: only the taken-over robot's movement ran, once")
        other.disconnect()
        driving.disconnect()
        second.close()
        first.close()
    }

    @Test
    fun aSessionARobotHasNoFreeLinkForFailsToOpenSayingWhy() = runBlocking<Unit> {
        val alice = connectBroker(broker.options("alice"))
        val device = alice.discoverer().discover().toList().map { it as BrokerRobotDevice }.first { it.gateway == "lab2" }
        val sessions = ArrayList<Transport>()
        // The firmware has 3 host links; other tests' sessions may hold some for a moment yet: open until refused.
        val refused = assertFailsWith<TransportLostException> { repeat(4) { sessions += device.open() } }
        assertTrue("in use" in refused.message!!, refused.message)
        sessions.forEach { it.close() }
        assertTrue(alice.connected.value)
        alice.close()
    }
}

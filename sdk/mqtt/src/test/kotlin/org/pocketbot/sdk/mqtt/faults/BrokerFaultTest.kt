package org.pocketbot.sdk.mqtt.faults

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.emulator.Speed
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.mqtt.BrokerOptions
import org.pocketbot.sdk.mqtt.connectBroker
import org.pocketbot.sdk.mqtt.startGateway
import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds

/**
 * Faults on the way between a fleet client and a robot, with what users get (the shipped broker configuration, the
 * SDK's default options), in real time: one emulated robot behind gateway `lab1`, driven by `alice` through one
 * broker. Each outage outlasts the robot's failsafe: the robot stops by itself, the handle ends FAILSAFE (or LOST)
 * with the distance really driven, nothing runs twice or late, and the client comes back by itself.
 */
class BrokerFaultTest {
    @Test
    fun theBrokerKilledMidMovementAndRestartedStopsTheRobotByItsFailsafeAndTheClientComesBack() = scene { s ->
        val handle = s.robot.locomotion.enqueue(CUT_MOVEMENT)
        delay(1.seconds)
        s.broker.kill()
        delay(2.seconds)
        assertStoppedByFailsafe(s.sim, "broker dead for 2 s")
        s.broker.restart()
        assertCutByFailsafe(s.robot, s.sim, s.start, handle)
        withTimeout(10.seconds) { s.client.connected.first { it } }
        assertNextMovementRunsOnce(s.robot, s.sim)
    }

    @Test
    fun aBrokerFrozenForThreeSecondsExecutesNothingLate() = scene { s ->
        val handle = s.robot.locomotion.enqueue(CUT_MOVEMENT)
        delay(1.seconds)
        s.broker.freeze()
        delay(3.seconds)
        assertStoppedByFailsafe(s.sim, "broker frozen for 3 s")
        val frozen = s.sim.trueWheelDistances
        s.broker.thaw()
        assertCutByFailsafe(s.robot, s.sim, s.start, handle)
        // What the broker held for 3 s reached the gateway, too late to be executed: the robot did not move on.
        assertTrue(s.gateway.stats.value.droppedLate > 0, "nothing dropped as late: ${s.gateway.stats.value}")
        assertTrue(s.sim.drivenSince(frozen) < 0.0005, "the robot moved after the freeze, by ${s.sim.drivenSince(frozen)} m")
        assertNextMovementRunsOnce(s.robot, s.sim)
    }

    @Test
    fun aKilledGatewayShowsOfflineAtOnceAndItsRobotStopsByItsFailsafe() = scene(gatewayCut = true) { s ->
        val handle = s.robot.locomotion.enqueue(CUT_MOVEMENT)
        delay(1.seconds)
        s.path.cut() // the gateway's host is gone: its connection breaks without a goodbye
        val cut = System.nanoTime()
        withTimeout(1.seconds) { s.client.gateways.first { it["lab1"]?.online == false } }
        println("gateway seen offline ${(System.nanoTime() - cut) / 1_000_000} ms after its connection broke")
        delay(1.5.seconds)
        assertStoppedByFailsafe(s.sim, "gateway dead")
        // Its robot links died with it; a new gateway process serves the robot again, and the client finds it.
        s.gateway.close()
        s.gateway = s.scope.startGateway("lab1", s.broker.options("lab1"), s.emu.discoverer())
        assertCutByFailsafe(s.robot, s.sim, s.start, handle)
        assertNextMovementRunsOnce(s.robot, s.sim)
    }

    @Test
    fun aClientCutOffForTwoSecondsReconnectsByItself() = scene(clientCut = true) { s ->
        val handle = s.robot.locomotion.enqueue(CUT_MOVEMENT)
        delay(1.seconds)
        s.path.cut()
        withTimeout(2.seconds) { s.client.connected.first { !it } }
        delay(2.seconds)
        assertStoppedByFailsafe(s.sim, "client cut off for 2 s")
        s.path.restore()
        assertCutByFailsafe(s.robot, s.sim, s.start, handle)
        assertEquals(true, s.client.connected.value)
        assertNextMovementRunsOnce(s.robot, s.sim)
    }

    private class Scene(
        val scope: CoroutineScope, val emu: Emulator, val sim: RobotHandle, val broker: MosquittoBroker,
        val path: CutProxy, var gateway: org.pocketbot.sdk.mqtt.Gateway, val client: org.pocketbot.sdk.mqtt.BrokerClient,
        val robot: org.pocketbot.sdk.Robot,
    ) {
        val start = sim.trueWheelDistances
    }

    /** One robot, its gateway and a client on one broker; [gatewayCut] or [clientCut] puts that side behind [Scene.path]. */
    private fun scene(gatewayCut: Boolean = false, clientCut: Boolean = false, body: suspend CoroutineScope.(Scene) -> Unit) =
        Emulator.local(robots = 1, world = "straight").use { emu ->
            emu.start(Speed.Realtime(1.0))
            MosquittoBroker.start().use { broker ->
                CutProxy(broker.tlsPort).use { path ->
                    fun options(user: String, cut: Boolean): BrokerOptions = if (cut) broker.optionsVia(path, user) else broker.options(user)
                    runBlocking {
                        val gateway = startGateway("lab1", options("lab1", gatewayCut), emu.discoverer())
                        val client = connectBroker(options("alice", clientCut))
                        val robot = client.robotOf("lab1").connect(this)
                        val s = Scene(this, emu, emu.robots.single(), broker, path, gateway, client, robot)
                        try {
                            body(s)
                        } finally {
                            robot.close()
                            client.close()
                            s.gateway.close()
                        }
                    }
                }
            }
            emu.stop()
        }
}

package org.pocketbot.sdk.mqtt.faults

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.mqtt.BrokerRobotDevice
import org.pocketbot.sdk.mqtt.connectBroker
import org.pocketbot.sdk.mqtt.startGateway
import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds

/**
 * A room broker bridged to a central broker with the shipped deploy/mosquitto/bridge.conf (only the central broker's
 * address, the bridge user's password and the CA replaced; the bridge runs through a [CutProxy] the test can cut):
 * gateway `lab1` with its own emulator on the central broker, gateway `lab2` with another on the room broker, and
 * `alice` on the central broker drives robots of both.
 */
class BridgedBrokersTest {
    @Test
    fun aClientOnTheCentralBrokerDrivesRobotsOfAGatewayOnEachBroker() = bridged { b ->
        val devices = withTimeout(10.seconds) { b.client.discoverer().discover().toList() }
        assertEquals(setOf("lab1", "lab2"), devices.map { (it as BrokerRobotDevice).gateway }.toSet(), "$devices")
        Fleet(this).use { fleet ->
            val robots = fleet.connectAll(devices)
            val starts = listOf(b.central, b.room).map { it.robots.single().trueWheelDistances }
            val results = robots.map { it.locomotion.enqueue(Movement.Straight(0.10, 0.1)) }.map { it.await() }
            assertTrue(results.all { it.outcome == MovementOutcome.FINISHED }, "$results")
            for ((emu, start) in listOf(b.central, b.room).zip(starts)) {
                assertEquals(0.10, emu.robots.single().drivenSince(start), 0.003, "the robot behind ${if (emu === b.room) "lab2" else "lab1"}")
            }
        }
    }

    @Test
    fun aCutBridgeStopsTheRoomsRobotByItsFailsafeAndTheClientRecoversWhenItIsBack() = bridged { b ->
        val sim = b.room.robots.single()
        b.client.robotOf("lab2").connect(this).use { robot ->
            val start = sim.trueWheelDistances
            val handle = robot.locomotion.enqueue(CUT_MOVEMENT)
            delay(1.seconds)
            b.bridge.cut()
            delay(2.seconds)
            assertStoppedByFailsafe(sim, "bridge cut for 2 s")
            b.bridge.restore()
            assertCutByFailsafe(robot, sim, start, handle)
            assertNextMovementRunsOnce(robot, sim)
        }
    }

    private class Bridged(val central: Emulator, val room: Emulator, val bridge: CutProxy, val client: org.pocketbot.sdk.mqtt.BrokerClient)

    private fun bridged(body: suspend CoroutineScope.(Bridged) -> Unit) =
        Emulator.local(robots = 1, world = "straight").use { centralEmu ->
            Emulator.local(robots = 1, world = "straight").use { roomEmu ->
                centralEmu.start(Speed.Realtime(1.0))
                roomEmu.start(Speed.Realtime(1.0))
                MosquittoBroker.start().use { central ->
                    CutProxy(central.tlsPort).use { bridge ->
                        startRoomBroker(central, bridge.port).use { room ->
                            runBlocking {
                                val lab1 = startGateway("lab1", central.options("lab1"), centralEmu.discoverer())
                                val lab2 = startGateway("lab2", room.options("lab2"), roomEmu.discoverer())
                                val client = connectBroker(central.options("alice"))
                                // The room's gateway is seen on the central broker once the bridge is up.
                                withTimeout(10.seconds) { client.gateways.first { it["lab2"]?.online == true } }
                                try {
                                    body(Bridged(centralEmu, roomEmu, bridge, client))
                                } finally {
                                    client.close()
                                    lab2.close()
                                    lab1.close()
                                }
                            }
                        }
                    }
                }
                roomEmu.stop()
                centralEmu.stop()
            }
        }
}

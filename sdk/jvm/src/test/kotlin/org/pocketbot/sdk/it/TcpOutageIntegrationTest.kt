package org.pocketbot.sdk.it

import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.protocol.LocoMode
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.transport.TcpRobotDevice
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/**
 * A real outage, as a user meets a flaky link: the emulated robot's TCP endpoint closes for half a second in the
 * middle of a one-metre movement and opens again on the same port, in real time. The SDK retries quickly while the
 * robot's failsafe (1000 ms, the default) waits, so the robot never stops and the movement finishes.
 */
class TcpOutageIntegrationTest {
    @Test
    fun aHalfSecondOutageOfTheRobotsEndpointIsBridgedBeforeItsFailsafeActs() = Emulator.local(robots = 1, world = "straight").use { emu ->
        val sim = emu.robots.single() // at the left end of the 1.2 m world, facing along it
        val port = sim.startTcp(0)
        emu.start(Speed.Realtime(1.0))
        runBlocking {
            val robot = TcpRobotDevice("127.0.0.1", port).connect(this)
            val start = sim.trueWheelDistances
            val handle = robot.locomotion.enqueue(Movement.Straight(1.0, 0.2))
            delay(1500)
            emu.stopTcp() // the host's connection drops and nothing answers on the port
            delay(500)
            sim.startTcp(port)
            val reopened = System.nanoTime()
            robot.connection.first { it == ConnectionState.Connected }
            val back = (System.nanoTime() - reopened) / 1_000_000
            println("reconnected $back ms after the endpoint reopened")
            val result = handle.await()
            val end = sim.trueWheelDistances
            assertEquals(MovementOutcome.FINISHED, result.outcome, "$result: the failsafe stopped the robot")
            assertEquals(1.0, (end.leftM - start.leftM + end.rightM - start.rightM) / 2, 0.01, "the whole metre, by the ground truth")
            assertTrue(sim.state().locomotion.mode != LocoMode.FAILSAFE)
            assertEquals(1L, robot.linkStats.value.reconnects)
            assertTrue(back < 1000, "reconnected $back ms after the endpoint came back: the failsafe would have acted")
            robot.disconnect()
        }
    }
}

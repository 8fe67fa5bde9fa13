package org.pocketbot.sdk.it

import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.connect
import kotlin.test.assertEquals

/** The SDK's own work runs on its own threads: user code that blocks the caller's thread cannot starve the link. */
class BlockingCallerIntegrationTest {
    @Test
    fun aCallerThatSleepsLongerThanTheFailsafeDoesNotStopTheRobot() {
        Emulator.local(robots = 1).use { emu ->
            emu.start(Speed.Realtime(1.0))
            runBlocking {
                val robot = emu.discoverer().discover().first().connect(this, itOptions())
                val handle = robot.locomotion.enqueue(Movement.Straight(0.25, 0.1))
                // runBlocking's only thread is busy for 3 s, three times the robot's default failsafe timeout.
                Thread.sleep(3_000)
                val result = handle.await()
                assertEquals(MovementOutcome.FINISHED, result.outcome, "the heartbeats stopped while the caller slept: $result")
                assertEquals(ConnectionState.Connected, robot.connection.value)
                assertEquals(0, robot.linkStats.value.reconnects)
                robot.close()
            }
        }
    }
}

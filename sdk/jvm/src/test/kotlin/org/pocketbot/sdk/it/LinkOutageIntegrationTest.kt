package org.pocketbot.sdk.it

import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.launch
import kotlinx.coroutines.yield
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.runSimulated
import org.pocketbot.sdk.ConnectionChange
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.LocoMode
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import kotlin.math.abs
import kotlin.test.assertEquals
import kotlin.test.assertNotNull
import kotlin.test.assertTrue
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * A link outage in the middle of a movement, with the settings users get (link failsafe 1000 ms): a 30 cm straight
 * at 0.1 m/s, and 1 s in the link drops for a while.
 */
class LinkOutageIntegrationTest {
    private class Run(val outcome: MovementOutcome, val doneM: Double?, val trueM: Double, val endedAfterReconnect: Duration, val movedAfterCutM: Double)

    private fun outage(length: Duration): Run = withEmulator(limit = 60.seconds) { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        val start = sim.trueWheelDistances
        val handle = robot.locomotion.enqueue(Movement.Straight(0.30, 0.1))
        delay(1.seconds)
        sim.disconnectLink()
        delay(length)
        sim.reconnectLink()
        val back = emu.time
        val result = handle.await()
        val ended = emu.time - back
        val atEnd = sim.trueWheelDistances
        delay(2.seconds)
        val later = sim.trueWheelDistances
        robot.close()
        Run(
            result.outcome, result.done, (atEnd.leftM - start.leftM + atEnd.rightM - start.rightM) / 2, ended,
            (later.leftM - atEnd.leftM + later.rightM - atEnd.rightM) / 2,
        )
    }

    @Test
    fun anOutageShorterThanTheFailsafeChangesNothing() {
        val run = outage(500.milliseconds)
        assertEquals(MovementOutcome.FINISHED, run.outcome)
        assertTrue(abs(run.trueM - 0.30) < 0.005, "drove ${run.trueM} m of 0.30")
        assertTrue(abs(run.doneM!! - run.trueM) < 0.005, "reported ${run.doneM} m, drove ${run.trueM} m")
    }

    @Test
    fun aTwoSecondOutageEndsTheMovementAsCutByTheFailsafeWithTheDistanceDone() = assertFailsafeCut(outage(2.seconds))

    @Test
    fun aTenSecondOutageEndsTheMovementAsCutByTheFailsafeWithTheDistanceDone() = assertFailsafeCut(outage(10.seconds))

    private fun assertFailsafeCut(run: Run) {
        assertEquals(MovementOutcome.FAILSAFE, run.outcome)
        val done = assertNotNull(run.doneM)
        // The failsafe trips 1 s after the host's last packet, which went out at most a heartbeat period (1/3 s)
        // before the outage at 1 s: the robot drove 1.7..2 s at up to 0.1 m/s, far from the 0.30 m it was asked for.
        assertTrue(run.trueM in 0.12..0.22, "drove ${run.trueM} m")
        assertTrue(abs(done - run.trueM) < 0.005, "reported $done m, ground truth ${run.trueM} m")
        assertTrue(run.endedAfterReconnect < 3.seconds, "the handle ended ${run.endedAfterReconnect} after the link came back")
        assertTrue(abs(run.movedAfterCutM) < 0.0005, "the robot moved ${run.movedAfterCutM} m after the failsafe stopped it")
    }

    @Test
    fun aLaterMovementDoesNotChangeAnEarlierHandlesResult() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        val cut = robot.locomotion.enqueue(Movement.Straight(0.30, 0.1))
        delay(1.seconds)
        sim.disconnectLink()
        delay(2.seconds)
        sim.reconnectLink()
        val first = cut.await()
        assertEquals(MovementOutcome.FAILSAFE, first.outcome)
        // The robot says why it stands: the failsafe, until the next command.
        robot.locomotion.state.first { robot.locomotion.mode == LocoMode.FAILSAFE }
        val next = robot.locomotion.enqueue(Movement.Straight(0.05, 0.1)).await()
        assertEquals(MovementOutcome.FINISHED, next.outcome)
        assertEquals(first, cut.await(), "an earlier result never changes")
        assertEquals(MovementOutcome.FAILSAFE, cut.resultOrNull?.outcome)
        robot.close()
    }

    @Test
    fun aRobotResetMidQueueEndsEveryPendingHandle() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        val handles = List(4) { robot.locomotion.enqueue(Movement.Straight(0.05, 0.1)) }
        delay(300.milliseconds)
        sim.reset()
        for (h in handles) {
            val r = h.await()
            assertTrue(r.outcome == MovementOutcome.LOST, "after the reset: $r")
        }
        robot.locomotion.awaitIdle()
        assertTrue(robot.locomotion.queue.value.isEmpty())
        // The robot works again after the reset.
        assertEquals(MovementOutcome.FINISHED, robot.locomotion.enqueue(Movement.Straight(0.02, 0.1)).await().outcome)
        robot.close()
    }

    @Test
    fun everyReconnectAttemptReachesTheChangesFlow() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        val changes = mutableListOf<ConnectionChange>()
        val collector = launch { robot.connectionChanges.collect { changes += it } }
        yield()
        sim.disconnectLink()
        delay(2.seconds)
        sim.reconnectLink()
        robot.connection.first { it == ConnectionState.Connected }
        collector.cancel()
        val attempts = changes.map { it.state }.filterIsInstance<ConnectionState.Reconnecting>().map { it.attempt }
        assertTrue(attempts.size >= 4, "a 2 s outage with a 250 ms backoff cap makes several attempts: $attempts")
        assertEquals((1..attempts.size).toList(), attempts, "every attempt, in order")
        assertEquals((changes.first().number until changes.first().number + changes.size).toList(), changes.map { it.number })
        robot.close()
    }

    @Test
    fun theSameScriptAndSeedGiveTheSameStateHashTwice() {
        fun script(): String = Emulator.local(robots = 2, world = "round").use { emu ->
            emu.runSimulated(30.seconds) {
                val (a, b) = connectAll(emu)
                a.locomotion.enqueue(Movement.Straight(0.1, 0.2))
                b.lineFollower.start()
                delay(1.seconds)
                emu.handleOf(a).disconnectLink()
                delay(1500.milliseconds)
                emu.handleOf(a).reconnectLink()
                a.locomotion.awaitIdle()
                b.settings.linePid.kd.set(0.003)
                delay(2.seconds)
                a.close(); b.close()
                emu.stateHash()
            }
        }
        assertEquals(script(), script())
    }
}

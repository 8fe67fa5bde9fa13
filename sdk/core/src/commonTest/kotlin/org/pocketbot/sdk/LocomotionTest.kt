@file:OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)

package org.pocketbot.sdk

import kotlinx.coroutines.async
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.test.advanceTimeBy
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.MoveArc
import org.pocketbot.protocol.MoveRotate
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.MovementDone
import org.pocketbot.protocol.MovementOutcome as Wire
import org.pocketbot.protocol.ReadMovements
import org.pocketbot.protocol.Stop
import org.pocketbot.protocol.WheelSpeeds
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertFalse
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds

class LocomotionTest {
    @Test
    fun movementsAreQueuedInOrderWithTheirParameters() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val a = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        val b = robot.locomotion.enqueue(Movement.Rotate(90.0, 0.2))
        val c = robot.locomotion.enqueue(Movement.Arc(0.05, -45.0, 0.1))
        assertSamePacket(MoveStraight(a.id, 0.1f, 0.2f), peer.executed[peer.executed.size - 3])
        assertSamePacket(MoveRotate(b.id, 90f, 0.2f), peer.executed[peer.executed.size - 2])
        assertSamePacket(MoveArc(c.id, 0.05f, -45f, 0.1f), peer.executed.last())
        assertEquals(listOf(a.id, b.id, c.id), peer.queue.toList())
        assertEquals(listOf(a, b, c), robot.locomotion.queue.value)
        robot.close()
    }

    @Test
    fun eachMovementEndsWithItsOwnReportAndHowMuchWasDone() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val a = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        val b = robot.locomotion.enqueue(Movement.Rotate(90.0, 0.2))
        val idle = async { robot.locomotion.awaitIdle() }
        peer.finishMovement(done = 0.0996f)
        val ra = a.await()
        assertEquals(MovementOutcome.FINISHED, ra.outcome)
        assertEquals(0.0996, ra.done!!, 1e-6)
        runCurrent()
        assertFalse(b.isDone)
        assertFalse(idle.isCompleted)
        peer.finishMovement(done = 89.5f)
        idle.await()
        assertEquals(MovementOutcome.FINISHED, b.await().outcome)
        assertEquals(89.5, b.await().done)
        assertTrue(robot.locomotion.queue.value.isEmpty())
        robot.close()
    }

    @Test
    fun aLaterReportNeverEndsAnEarlierMovementAsFinished() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val a = robot.locomotion.enqueue(Movement.Straight(0.3, 0.1))
        val b = robot.locomotion.enqueue(Movement.Straight(0.1, 0.1))
        // a was cut short and its report lost; b then finished and says so.
        peer.finishMovement(announce = false, outcome = Wire.FAILSAFE, done = 0.104f)
        peer.finishMovement(announce = true)
        assertEquals(MovementOutcome.FINISHED, b.await().outcome)
        // The gap makes the SDK read the robot's log, which knows how a really ended.
        val ra = a.await()
        assertEquals(MovementOutcome.FAILSAFE, ra.outcome)
        assertEquals(0.104, ra.done!!, 1e-6)
        assertTrue(peer.executed.any { it is ReadMovements })
        robot.close()
    }

    @Test
    fun aLostLastReportIsRecoveredFromTheLogOnceTheRobotStandsIdle() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, testOptions(syncMode = SyncMode.FULL))
        val a = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        peer.finishMovement(announce = false, done = 0.1f)
        // The robot keeps sending state: idle, queue empty.
        repeat(20) { i ->
            peer.sendState(peer.state.withTime(1000L + 100 * i))
            advanceTimeBy(100)
        }
        assertEquals(MovementOutcome.FINISHED, a.await().outcome)
        robot.close()
    }

    @Test
    fun aReportGarbledOnTheWayIsRecoveredFromTheLogWithoutFullState() = runTest {
        val peer = ScriptedRobot()
        // Reduced state carries no locomotion: only the log can tell that the movement ended.
        val robot = connect(peer, testOptions(syncMode = SyncMode.REDUCED))
        val a = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        peer.garbleOutgoingIf = { it is MovementDone }
        peer.finishMovement(announce = true, done = 0.0995f)
        val result = a.await()
        assertEquals(MovementOutcome.FINISHED, result.outcome)
        assertEquals(0.0995, result.done!!, 1e-6)
        assertEquals(1, robot.linkStats.value.badCrc)
        assertEquals(0, robot.linkStats.value.reconnects, "found on the live link, not by a reconnect")
        robot.locomotion.awaitIdle()
        robot.close()
    }

    @Test
    fun stopEndsTheRunningMovementAsStoppedAndTheQueuedOnesAsDropped() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val a = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        val b = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        robot.locomotion.stop(immediate = true)
        assertEquals(Stop(1), peer.executed.last())
        assertEquals(MovementOutcome.STOPPED, a.await().outcome)
        assertEquals(MovementOutcome.DROPPED, b.await().outcome)
        assertEquals(0.0, b.await().done)
        assertTrue(peer.queue.isEmpty())
        robot.close()
    }

    @Test
    fun stopGoesOutAheadOfACommandWaitingForItsAck() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        // The robot does not answer the move (lost on the way); the stop must not wait behind its retransmissions.
        peer.dropIncoming = 1
        val move = async { robot.locomotion.enqueue(Movement.Straight(0.1, 0.2)) }
        runCurrent()
        robot.locomotion.stop()
        assertEquals(Stop(0), peer.executed.last(), "the stop was executed before the move was retransmitted")
        assertFalse(peer.executed.any { it is MoveStraight })
        // The move was withdrawn: it never reached the robot, and says so.
        val h = move.await()
        val r = h.await()
        assertEquals(MovementOutcome.DROPPED, r.outcome)
        assertFalse(peer.executed.any { it is MoveStraight }, "a withdrawn move must not be retransmitted after the stop")
        robot.close()
    }

    @Test
    fun stopDuringAnOutageGoesFirstAfterTheReconnectAndWithdrawsUnsentMoves() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val running = robot.locomotion.enqueue(Movement.Straight(0.3, 0.1))
        peer.refuseOpens = 2
        peer.disconnect()
        runCurrent()
        val later = async { robot.locomotion.enqueue(Movement.Straight(0.1, 0.1)) }
        val stop = async { robot.locomotion.stop() }
        runCurrent()
        stop.await()
        val afterHandshake = peer.executed.dropWhile { it !is Stop }
        assertTrue(afterHandshake.isNotEmpty(), "the stop was executed")
        assertFalse(peer.executed.any { it is MoveStraight && it.id == later.await().id }, "the move issued before the stop must not be sent")
        assertEquals(MovementOutcome.DROPPED, later.await().await().outcome)
        assertEquals(MovementOutcome.STOPPED, running.await().outcome)
        robot.close()
    }

    @Test
    fun aFullQueueIsATypedRefusal() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        repeat(8) { robot.locomotion.enqueue(Movement.Straight(0.01, 0.2)) }
        val e = assertFailsWith<CommandRefusedException> { robot.locomotion.enqueue(Movement.Straight(0.01, 0.2)) }
        assertEquals(ErrorCode.QUEUE_FULL, e.code)
        assertEquals("move_straight", e.command)
        assertEquals(8, robot.locomotion.queue.value.size, "the refused one is not in the queue")
        robot.close()
    }

    @Test
    fun wheelSpeedsGoOutUnacknowledged() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        assertTrue(robot.locomotion.setWheelSpeeds(0.1, -0.1))
        assertSamePacket(WheelSpeeds(0.1f, -0.1f), peer.received.last().second)
        robot.close()
    }

    @Test
    fun aRobotResetMidQueueEndsEveryPendingHandle() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val handles = List(3) { robot.locomotion.enqueue(Movement.Straight(0.1, 0.1)) }
        peer.reset()
        advanceTimeBy(5.seconds)
        for (h in handles) {
            val r = h.await()
            assertEquals(MovementOutcome.LOST, r.outcome)
            assertNull(r.done)
        }
        robot.locomotion.awaitIdle()
        robot.close()
    }

    @Test
    fun invalidMovementsAreRejectedBeforeSending() {
        assertFailsWith<IllegalArgumentException> { Movement.Straight(0.1, 0.0) }
        assertFailsWith<IllegalArgumentException> { Movement.Arc(0.0, 90.0, 0.1) }
        assertFailsWith<IllegalArgumentException> { Movement.Rotate(Double.NaN, 0.1) }
    }
}

@file:OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)

package org.pocketbot.sdk

import kotlinx.coroutines.async
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.ErrorCode
import org.pocketbot.protocol.MoveArc
import org.pocketbot.protocol.MoveRotate
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.Stop
import org.pocketbot.protocol.WheelSpeeds
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertFalse
import kotlin.test.assertTrue

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
        robot.close()
    }

    @Test
    fun awaitReturnsWhenTheRobotReportsTheMovementDone() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val a = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        val b = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        val idle = async { robot.locomotion.awaitIdle() }
        peer.finishMovement()
        assertEquals(MovementResult.FINISHED, a.await())
        runCurrent()
        assertFalse(b.isDone)
        assertFalse(idle.isCompleted)
        peer.finishMovement()
        idle.await()
        assertEquals(MovementResult.FINISHED, b.await())
        robot.close()
    }

    @Test
    fun aLaterFinishImpliesTheEarlierOnesFinished() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val a = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        val b = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        peer.finishMovement(announce = false)
        peer.finishMovement(announce = true)
        assertEquals(MovementResult.FINISHED, a.await())
        assertEquals(MovementResult.FINISHED, b.await())
        robot.close()
    }

    @Test
    fun staleFinishedIdFromAnEarlierSessionFinishesNothing() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.sendState()
        runCurrent()
        val a = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        // The robot still reports the same finished id as before: nothing changed, nothing finished.
        peer.sendState()
        runCurrent()
        assertFalse(a.isDone)
        peer.finishMovement(announce = false)
        peer.sendState()
        assertEquals(MovementResult.FINISHED, a.await())
        robot.close()
    }

    @Test
    fun stopCancelsQueuedMovements() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val a = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        robot.locomotion.stop(immediate = true)
        assertEquals(MovementResult.CANCELLED, a.await())
        assertEquals(Stop(1), peer.executed.last())
        assertTrue(peer.queue.isEmpty())
        robot.close()
    }

    @Test
    fun aFullQueueIsATypedRefusal() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        repeat(8) { robot.locomotion.enqueue(Movement.Straight(0.01, 0.2)) }
        val e = assertFailsWith<CommandRefusedException> { robot.locomotion.enqueue(Movement.Straight(0.01, 0.2)) }
        assertEquals(ErrorCode.QUEUE_FULL, e.code)
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
    fun invalidMovementsAreRejectedBeforeSending() {
        assertFailsWith<IllegalArgumentException> { Movement.Straight(0.1, 0.0) }
        assertFailsWith<IllegalArgumentException> { Movement.Arc(0.0, 90.0, 0.1) }
    }
}

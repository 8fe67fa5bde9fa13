@file:OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)

package org.pocketbot.sdk

import kotlinx.coroutines.async
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.SyncMode
import org.pocketbot.protocol.UpdateSettings
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertIs
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

class LinkLossTest {
    @Test
    fun lossIsReportedAtOnceThenTheSdkReconnectsAndResendsTheSyncMode() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.reflector.set(SyncMode.REDUCED, 10.milliseconds)
        peer.refuseOpens = 2
        peer.disconnect()
        runCurrent()
        assertIs<ConnectionState.Lost>(robot.connection.value, "a loss must show at once")
        robot.connection.first { it == ConnectionState.Connected }
        assertEquals(4, peer.opens, "first open, two refused, one good")
        assertEquals(1, robot.linkStats.value.reconnects)
        assertEquals(SetSync(2, 10), peer.executed.last(), "the sync mode is re-sent after the reconnect")
        robot.close()
    }

    @Test
    fun commandIssuedWhileLostWaitsAndGoesOutAfterReconnect() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.refuseOpens = 3
        peer.disconnect()
        runCurrent()
        robot.settings.linePid.kp.set(2f)
        assertEquals(1, peer.executed.count { it is UpdateSettings })
        assertEquals(2f, robot.settings.linePid.kp.value)
        robot.close()
    }

    @Test
    fun movementInFlightAtTheLossIsExecutedExactlyOnce() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        // The robot executes the move but the link dies before its ack gets out.
        peer.dropOutgoingIf = { it is org.pocketbot.protocol.Ack && it.ackedType == MoveStraight.TYPE }
        val handle = async { robot.locomotion.enqueue(Movement.Straight(0.1, 0.2)) }
        runCurrent()
        assertEquals(1, peer.executed.count { it is MoveStraight })
        peer.dropOutgoingIf = null
        peer.disconnect()
        val h = handle.await()
        val moves = peer.received.filter { it.second is MoveStraight }
        assertTrue(moves.size >= 2, "the move must have been retransmitted after the reconnect")
        assertTrue(moves.all { it.first == moves[0].first }, "every retransmission keeps the sequence number")
        assertEquals(1, peer.executed.count { it is MoveStraight }, "executed twice")
        assertEquals(h.id, (peer.executed.single { it is MoveStraight } as MoveStraight).id)
        robot.close()
    }

    @Test
    fun unconfirmedSettingIsResentAfterTheReconnectWithItsSeqAndAppliedOnce() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        // The write reaches the robot, its ack is lost, then the link breaks.
        peer.dropOutgoingIf = { it is org.pocketbot.protocol.Ack && it.ackedType == UpdateSettings.TYPE }
        val write = async { robot.settings.linePid.kp.set(4f) }
        runCurrent()
        peer.dropOutgoingIf = null
        peer.disconnect()
        write.await()
        val sent = peer.received.filter { it.second is UpdateSettings }
        assertTrue(sent.size >= 2, "the unconfirmed write must be re-sent after the reconnect")
        assertTrue(sent.all { it.first == sent[0].first }, "with the same sequence number")
        assertEquals(1, peer.executed.count { it is UpdateSettings })
        assertEquals(4f, robot.settings.linePid.kp.value)
        robot.close()
    }

    @Test
    fun movementDoneLostDuringTheOutageIsRecoveredFromTheState() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val h = robot.locomotion.enqueue(Movement.Straight(0.1, 0.2))
        peer.sendState()
        runCurrent()
        peer.disconnect()
        peer.finishMovement(announce = false) // finishes while nobody listens
        runCurrent()
        robot.connection.first { it == ConnectionState.Connected }
        peer.sendState()
        assertEquals(MovementResult.FINISHED, h.await())
        robot.close()
    }

    @Test
    fun givingUpClosesTheRobotAndFailsWaitingCommands() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, testOptions(reconnect = ReconnectPolicy(10.milliseconds, 20.milliseconds, maxAttempts = 3)))
        peer.refuseOpens = 100
        peer.disconnect()
        val pending = async { runCatching { robot.settings.linePid.kp.set(2f) } }
        val closed = robot.connection.first { it is ConnectionState.Closed } as ConnectionState.Closed
        assertIs<RobotClosedException>(closed.cause)
        assertIs<RobotClosedException>(pending.await().exceptionOrNull())
        assertFailsWith<RobotClosedException> { robot.locomotion.stop() }
    }

    @Test
    fun closeFailsCommandsStillWaiting() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.dropIncoming = 1000
        val pending = async { runCatching { robot.settings.linePid.kp.set(2f) } }
        runCurrent()
        robot.close()
        assertIs<RobotClosedException>(pending.await().exceptionOrNull())
    }
}

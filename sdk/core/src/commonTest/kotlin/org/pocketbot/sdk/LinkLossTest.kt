@file:OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)

package org.pocketbot.sdk

import kotlinx.coroutines.async
import kotlinx.coroutines.launch
import kotlinx.coroutines.withTimeoutOrNull
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.test.advanceTimeBy
import kotlinx.coroutines.test.currentTime
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.UpdateSettings
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFalse
import kotlin.test.assertFailsWith
import kotlin.test.assertIs
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

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
        awaitReconnect(robot)
        assertEquals(4, peer.opens, "first open, two refused, one good")
        assertEquals(1, robot.linkStats.value.reconnects)
        assertEquals(SetSync(2, 10), peer.executed.last(), "the sync mode is re-sent after the reconnect")
        robot.close()
    }

    @Test
    fun aLinkThatComesBackAfterALongOutageIsNoticedWithinTheBackoffCap() = runTest {
        val peer = ScriptedRobot()
        val policy = ReconnectPolicy() // what users get
        val robot = connect(peer, testOptions(reconnect = policy))
        peer.refuseOpens = Int.MAX_VALUE
        peer.disconnect()
        advanceTimeBy(10_000) // ten seconds down: the backoff reached its cap long ago
        peer.refuseOpens = 0
        val back = currentTime
        robot.connection.first { it == ConnectionState.Connected }
        val noticedAfter = currentTime - back
        assertTrue(noticedAfter <= policy.maxDelay.inWholeMilliseconds, "back after $noticedAfter ms, cap ${policy.maxDelay}")
        robot.close()
    }

    @Test
    fun commandIssuedWhileLostWaitsAndGoesOutAfterReconnect() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.refuseOpens = 3
        peer.disconnect()
        runCurrent()
        robot.settings.linePid.kp.set(2.0)
        assertEquals(1, peer.executed.count { it is UpdateSettings })
        assertEquals(2.0, robot.settings.linePid.kp.value)
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
        // After the reconnect the robot's log shows it holds the move: it is taken as acknowledged, not sent again.
        val moves = peer.received.filter { it.second is MoveStraight }
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
        val write = async { robot.settings.linePid.kp.set(4.0) }
        runCurrent()
        peer.dropOutgoingIf = null
        peer.disconnect()
        write.await()
        val sent = peer.received.filter { it.second is UpdateSettings }
        assertTrue(sent.size >= 2, "the unconfirmed write must be re-sent after the reconnect")
        assertTrue(sent.all { it.first == sent[0].first }, "with the same sequence number")
        assertEquals(1, peer.executed.count { it is UpdateSettings })
        assertEquals(4.0, robot.settings.linePid.kp.value)
        robot.close()
    }

    @Test
    fun movementEndedDuringTheOutageIsReconciledFromTheRobotsLog() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val cut = robot.locomotion.enqueue(Movement.Straight(0.3, 0.1))
        val queued = robot.locomotion.enqueue(Movement.Straight(0.1, 0.1))
        peer.refuseOpens = 2
        peer.disconnect()
        // The failsafe ends both while nobody listens: the reports are lost, the log keeps them.
        peer.clearQueue(org.pocketbot.protocol.MovementOutcome.FAILSAFE, doneRunning = 0.104f, announce = false)
        awaitReconnect(robot)
        val r = cut.await()
        assertEquals(MovementOutcome.FAILSAFE, r.outcome)
        assertEquals(0.104, r.done!!, 1e-6)
        assertEquals(MovementOutcome.FAILSAFE, queued.await().outcome)
        assertEquals(0.0, queued.await().done)
        robot.locomotion.awaitIdle()
        robot.close()
    }

    @Test
    fun movementStillRunningAfterAShortOutageFinishesExactlyOnce() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val h = robot.locomotion.enqueue(Movement.Straight(0.1, 0.1))
        peer.disconnect()
        awaitReconnect(robot)
        runCurrent()
        assertFalse(h.isDone, "the robot still runs it")
        peer.finishMovement()
        assertEquals(MovementOutcome.FINISHED, h.await().outcome)
        assertEquals(1, peer.executed.count { it is MoveStraight })
        robot.close()
    }

    @Test
    fun everyReconnectAttemptIsSeenInTheChanges() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val seen = mutableListOf<ConnectionChange>()
        val collector = launch { robot.connectionChanges.collect { seen += it } }
        runCurrent()
        peer.refuseOpens = 3
        peer.disconnect()
        awaitReconnect(robot)
        runCurrent()
        collector.cancel()
        val states = seen.map { it.state }
        assertEquals(listOf(1, 2, 3, 4), states.filterIsInstance<ConnectionState.Reconnecting>().map { it.attempt })
        assertEquals(ConnectionState.Connected, states.last())
        assertEquals((seen.first().number until seen.first().number + seen.size).toList(), seen.map { it.number }, "numbered without gaps")
        robot.close()
    }

    @Test
    fun aResetStormNeverHangsTheHost() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        // A broken robot: it announces itself unasked again and again and never acknowledges set_sync.
        peer.refuseToAck = { it is SetSync }
        repeat(300) { peer.sayHelloUnasked() }
        runCurrent()
        val write = withTimeoutOrNull(5.seconds) { robot.settings.linePid.kp.set(1.0) }
        // The write may or may not get through the storm, but it returns: nothing spins, nothing piles up.
        assertTrue(write == null || robot.settings.linePid.kp.value == 1.0)
        robot.close()
        assertIs<ConnectionState.Closed>(robot.connection.value)
    }

    @Test
    fun givingUpClosesTheRobotAndFailsWaitingCommands() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, testOptions(reconnect = ReconnectPolicy { initialDelay = 10.milliseconds; maxDelay = 20.milliseconds; maxAttempts = 3 }))
        peer.refuseOpens = 100
        peer.disconnect()
        val pending = async { runCatching { robot.settings.linePid.kp.set(2.0) } }
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
        val pending = async { runCatching { robot.settings.linePid.kp.set(2.0) } }
        runCurrent()
        robot.close()
        assertIs<RobotClosedException>(pending.await().exceptionOrNull())
    }
}

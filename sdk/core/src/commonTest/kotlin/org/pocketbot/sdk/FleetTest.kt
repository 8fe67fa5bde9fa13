package org.pocketbot.sdk

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.async
import kotlinx.coroutines.awaitCancellation
import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.asFlow
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.flow
import kotlinx.coroutines.launch
import kotlinx.coroutines.plus
import kotlinx.coroutines.test.currentTime
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.RobotDevice
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertIs
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds

class FleetTest {
    @Test
    fun discoverConnectMoveTogetherAndCloseAll() = runTest {
        val peers = (1..3).map { ScriptedRobot(robotId = it, name = "R$it") }
        val discoverer = object : Discoverer {
            override fun discover(): Flow<RobotDevice> = peers.map { it.device }.asFlow()
        }
        val fleet = Fleet(robotScope(), testOptions())
        val robots = fleet.discoverAndConnect(discoverer)
        assertEquals(listOf(1, 2, 3), robots.map { it.identity.robotId }.sorted())
        assertEquals(3, fleet.robots.value.size)

        val handles = fleet.enqueueTogether(robots.associateWith { Movement.Straight(0.05, 0.1) })
        for (peer in peers) {
            val move = peer.executed.filterIsInstance<MoveStraight>().single()
            assertF32(0.05f, move.distanceM)
        }
        peers.forEach { it.finishMovement() }
        fleet.awaitIdle()
        assertTrue(handles.values.all { it.isDone })

        fleet.close()
        robots.forEach { assertIs<ConnectionState.Closed>(it.connection.value) }
        assertTrue(fleet.robots.value.isEmpty())
    }

    @Test
    fun enqueueTogetherSendsAllFramesBackToBack() = runTest {
        val peers = (1..4).map { ScriptedRobot(robotId = it) }
        val fleet = Fleet(robotScope(), testOptions())
        val robots = fleet.connectAll(peers.map { it.device })
        // Something already in flight on one robot must not hold the others back longer than itself.
        val before = peers.map { it.received.size }
        fleet.enqueueTogether(robots.associateWith { Movement.Rotate(90.0, 0.1) })
        peers.forEachIndexed { i, p -> assertEquals(before[i] + 1, p.received.size) }
        fleet.close()
    }

    @Test
    fun aRobotThatRefusesDoesNotHoldTheOthersBack() = runTest {
        val peers = (1..3).map { ScriptedRobot(robotId = it) }
        val fleet = Fleet(robotScope(), testOptions())
        val robots = fleet.connectAll(peers.map { it.device })
        repeat(8) { robots[0].locomotion.enqueue(Movement.Straight(0.01, 0.1)) } // its queue is full
        val failure = runCatching { fleet.enqueueTogether(robots.associateWith { Movement.Straight(0.05, 0.1) }) }
        assertIs<CommandRefusedException>(failure.exceptionOrNull())
        assertEquals(1, peers[1].executed.count { it is MoveStraight }, "the others still got theirs")
        fleet.close()
    }

    @Test
    fun oneFailingConnectClosesTheOthers() = runTest {
        val good = ScriptedRobot(robotId = 1)
        val bad = ScriptedRobot(robotId = 2).apply { answersHello = false }
        val fleet = Fleet(robotScope(), testOptions())
        val failure = runCatching { fleet.connectAll(listOf(good.device, bad.device)) }.exceptionOrNull()
        assertIs<ConnectFailedException>(failure)
        assertTrue(fleet.robots.value.isEmpty())
        fleet.close()
    }

    @Test
    fun discoverAndConnectFailsWhenFewerRobotsTurnUpAndNamesThem() = runTest {
        val peers = (1..2).map { ScriptedRobot(robotId = it, name = "R$it") }
        val discoverer = object : Discoverer {
            override fun discover(): Flow<RobotDevice> = flow {
                peers.forEach { emit(it.device) }
                awaitCancellation() // a discoverer keeps looking
            }
        }
        val fleet = Fleet(robotScope(), testOptions())
        val e = assertFailsWith<RobotsNotFoundException> { fleet.discoverAndConnect(discoverer, count = 3, timeout = 2.seconds) }
        assertEquals(3, e.wanted)
        assertEquals(peers.map { it.device }, e.found)
        assertTrue("found 2 of 3 robots" in e.message!! && peers.all { it.device.name in e.message!! }, e.message)
        assertTrue(fleet.robots.value.isEmpty() && peers.none { it.connected }, "nothing connected")
        assertEquals(2, fleet.discoverAndConnect(discoverer, count = 2).size)
        fleet.close()
    }

    @Test
    fun cancellingConnectAllPropagatesAndClosesThoseThatConnected() = runTest {
        val quick = ScriptedRobot(robotId = 1)
        val silent = ScriptedRobot(robotId = 2).apply { answersHello = false } // its connect takes 4 hello timeouts
        val fleet = Fleet(robotScope(), testOptions())
        val connecting = async { fleet.connectAll(listOf(quick.device, silent.device)) }
        runCurrent()
        fleet.robots.first { it.size == 1 }
        connecting.cancel()
        assertFailsWith<CancellationException> { connecting.await() }
        assertTrue(fleet.robots.value.isEmpty(), "the robot that connected is removed")
        assertTrue(!quick.connected && !silent.connected, "both links closed")
        fleet.close()
    }

    @Test
    fun aFleetOnAScopeThatEndedSaysSoAndAClosedFleetConnectsNothing() = runTest {
        val e = assertFailsWith<IllegalStateException> { Fleet(CoroutineScope(Job().apply { cancel() })) }
        assertTrue("scope has ended" in e.message!!, e.message)
        val fleet = Fleet(robotScope(), testOptions())
        fleet.close()
        assertFailsWith<IllegalStateException> { fleet.connect(ScriptedRobot().device) }
    }

    @Test
    fun theScopeThatMadeAFleetWaitsForItsCloseAndCancellingItClosesTheRobots() = runTest {
        val peers = (1..2).map { ScriptedRobot(robotId = it) }
        lateinit var robots: List<Robot>
        coroutineScope {
            val fleet = Fleet(this + runtime(), testOptions())
            robots = fleet.connectAll(peers.map { it.device })
            launch {
                delay(3.seconds)
                fleet.close()
            }
        }
        assertTrue(currentTime >= 3000, "the scope returned at $currentTime ms, before the fleet closed")
        assertTrue(peers.none { it.connected })

        val again = (3..4).map { ScriptedRobot(robotId = it) }
        val started = CompletableDeferred<List<Robot>>()
        val scope = launch { started.complete(Fleet(this + runtime(), testOptions()).connectAll(again.map { it.device })) }
        val second = started.await()
        scope.cancel()
        scope.join()
        second.forEach { assertIs<ConnectionState.Closed>(it.connection.value) }
        assertTrue(again.none { it.connected })
    }
}

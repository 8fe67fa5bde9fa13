package org.pocketbot.sdk

import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.asFlow
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.RobotDevice
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertIs
import kotlin.test.assertTrue

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
}

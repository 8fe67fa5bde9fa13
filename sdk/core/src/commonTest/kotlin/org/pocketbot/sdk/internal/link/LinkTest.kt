@file:OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)

package org.pocketbot.sdk.internal.link

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.async
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.test.TestScope
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.Ack
import org.pocketbot.protocol.DebugText
import org.pocketbot.protocol.Driver
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.SaveSettings
import org.pocketbot.protocol.StateFull
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.DebugLog
import org.pocketbot.sdk.ScriptedRobot
import org.pocketbot.sdk.WIRE_EMPTY
import org.pocketbot.sdk.runtime
import org.pocketbot.sdk.testOptions
import kotlin.random.Random
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertIs
import kotlin.test.assertTrue
import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds

/** The link on its own, without a Robot: a scripted peer on one side, a recording client on the other. */
class LinkTest {
    private class RecordingClient : LinkClient {
        val packets = mutableListOf<Packet>()
        val restores = mutableListOf<Boolean>()
        var drops = 0
        var held: (Packet) -> Boolean = { false }
        var restoreWith: Packet? = null

        override fun onPacket(packet: Packet) {
            packets += packet
        }

        override suspend fun restore(hello: Hello, firstSession: Boolean, driver: Driver, exchange: suspend (Packet) -> Unit) {
            restores += firstSession
            restoreWith?.let { exchange(it) }
        }

        override fun onFrameDropped() {
            drops++
        }

        override fun alreadyHeld(packet: Packet): Boolean = held(packet)
        override val silenceTimeout: Duration? get() = null
        override val heartbeatPeriod: Duration get() = 1.seconds
    }

    private fun TestScope.link(peer: ScriptedRobot, client: LinkClient): Link {
        // A child of the test: a failing test ends the link too, instead of leaving it to run on virtual time.
        val lifetime = Job(backgroundScope.coroutineContext[Job])
        val job = SupervisorJob(lifetime)
        val serial = runtime().dispatcher.limitedParallelism(1) // as a Robot runs its link
        return Link(peer.device, testOptions(), serial, CoroutineScope(serial + job), job, lifetime, DebugLog(), Random(1))
            .also { it.client = client }
    }

    @Test
    fun packetsTheLinkDoesNotConsumeReachTheClientInOrder() = runTest {
        val peer = ScriptedRobot()
        val client = RecordingClient()
        val link = link(peer, client)
        link.start()
        assertEquals(ConnectionState.Connected, link.connection.value)
        assertEquals(listOf(true), client.restores, "the first session is restored once")
        assertEquals(peer.robotId, link.identity.value?.robotId)
        peer.send(StateFull(WIRE_EMPTY))
        peer.send(DebugText(0, 2, "hello".encodeToByteArray()))
        peer.sendRaw(byteArrayOf(1, 2, 3)) // not a frame: counted, not handed on
        runCurrent()
        assertEquals(listOf(StateFull::class, DebugText::class), client.packets.map { it::class })
        assertEquals(1, client.drops)
        assertEquals(1, link.linkStats.value.tooShort)
        link.close(null)
    }

    @Test
    fun aStateIsCountedBeforeTheClientSeesIt() = runTest {
        val peer = ScriptedRobot()
        lateinit var link: Link
        val countsSeen = mutableListOf<Long>()
        val client = object : LinkClient by RecordingClient() {
            override fun onPacket(packet: Packet) {
                if (packet is StateFull) countsSeen += link.linkStats.value.fullStates
            }
        }
        link = link(peer, client)
        link.start()
        repeat(3) { peer.send(StateFull(WIRE_EMPTY)) }
        runCurrent()
        assertEquals(listOf(1L, 2L, 3L), countsSeen, "the link's count already includes the state its client is handed")
        link.close(null)
    }

    @Test
    fun aLostAckIsRetransmittedWithTheSameNumberAndExecutedOnce() = runTest {
        val peer = ScriptedRobot()
        val link = link(peer, RecordingClient())
        link.start()
        peer.dropOutgoing = 1 // the ack of the first try
        link.command(SaveSettings)
        val sent = peer.received.filter { it.second == SaveSettings }
        assertEquals(2, sent.size, "sent twice")
        assertEquals(1, sent.map { it.first }.distinct().size, "with one sequence number")
        assertEquals(1, peer.executed.count { it == SaveSettings }, "executed once")
        assertEquals(1, link.linkStats.value.retransmissions)
        link.close(null)
    }

    @Test
    fun afterALossTheRestoreRunsBeforeTheCommandInFlightGoesOutAgain() = runTest {
        val peer = ScriptedRobot()
        val client = RecordingClient()
        val link = link(peer, client)
        link.start()
        client.restoreWith = SaveSettings
        // The robot takes the move, then the link dies before its ack gets out.
        peer.dropOutgoingIf = { it is Ack && it.ackedType == MoveStraight.TYPE }
        val move = MoveStraight(5, 0.125f, 0.25f)
        val done = async { link.command(move) }
        runCurrent()
        peer.dropOutgoingIf = null
        peer.disconnect()
        done.await()
        assertEquals(listOf(true, false), client.restores)
        val afterReconnect = peer.received.map { it.second }.dropWhile { it != move }.drop(1)
        assertEquals(SaveSettings, afterReconnect.first { it == SaveSettings || it == move }, "restore first, then the resend")
        assertEquals(1, peer.executed.count { it == move }, "the retransmission is recognised, not executed again")
        link.close(null)
    }

    @Test
    fun aCommandTheRobotAlreadyHoldsIsNotSentAgainAfterTheReconnect() = runTest {
        val peer = ScriptedRobot()
        val client = RecordingClient()
        val link = link(peer, client)
        link.start()
        val move = MoveStraight(9, 0.125f, 0.25f)
        client.held = { it == move }
        peer.dropOutgoingIf = { it is Ack && it.ackedType == MoveStraight.TYPE }
        val done = async { link.command(move) }
        runCurrent()
        peer.dropOutgoingIf = null
        peer.disconnect()
        done.await()
        assertEquals(1, peer.received.count { it.second == move }, "the robot's log showed it: no second transmission")
        link.close(null)
    }

    @Test
    fun aHelloNobodyAskedForEndsTheSessionAndTheNextOneIsRestored() = runTest {
        val peer = ScriptedRobot()
        val client = RecordingClient()
        val link = link(peer, client)
        link.start()
        peer.reset()
        runCurrent()
        assertIs<ConnectionState.Lost>(link.connection.value)
        link.connection.first { it == ConnectionState.Connected }
        assertEquals(listOf(true, false), client.restores)
        assertEquals(2, peer.opens)
        link.close(null)
    }
}

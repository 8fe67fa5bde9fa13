package org.pocketbot.sdk

import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.delay
import kotlinx.coroutines.launch
import kotlinx.coroutines.plus
import kotlinx.coroutines.test.currentTime
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.SetSync
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertIs
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds

class ConnectTest {
    @Test
    fun handshakeLearnsIdentitySettingsAndStartsSync() = runTest {
        val peer = ScriptedRobot(robotId = 9, name = "Nine")
        peer.poke("line_pid.kp", 0.0009765625) // not the default: only a real read can know it
        val robot = connect(peer, testOptions(syncMode = SyncMode.FULL))
        assertEquals(ConnectionState.Connected, robot.connection.value)
        assertEquals(9, robot.identity.robotId)
        assertEquals("Nine", robot.identity.name)
        assertEquals("0.1.0", robot.identity.firmwareVersion)
        assertEquals(9, robot.settings.identity.robotId.value)
        assertEquals(0.0009765625, robot.settings.linePid.kp.value)
        assertEquals(1, peer.executed.count { it is ReadSettings })
        val sync = peer.executed.filterIsInstance<SetSync>().single()
        assertEquals(SyncMode.FULL.code, sync.mode)
        assertEquals(100, sync.periodMs)
        assertEquals(SyncMode.FULL, robot.reflector.mode.value)
        robot.close()
        assertIs<ConnectionState.Closed>(robot.connection.value)
    }

    @Test
    fun protocolMismatchNamesBothVersions() = runTest {
        val peer = ScriptedRobot(protocolVersion = 99, layoutHash = 0x12345678)
        val e = assertFailsWith<ProtocolMismatchException> { connect(peer) }
        assertTrue("v99" in e.message!! && "v${ProtocolInfo.VERSION}" in e.message!!, e.message)
        assertTrue("0x12345678" in e.message!!, e.message)
        assertEquals(99, e.robotVersion)
    }

    @Test
    fun layoutMismatchAloneFailsToo() = runTest {
        val peer = ScriptedRobot(layoutHash = ProtocolInfo.LAYOUT_HASH xor 1)
        assertFailsWith<ProtocolMismatchException> { connect(peer) }
    }

    @Test
    fun silentRobotFailsWithConnectFailedCausedByATimeout() = runTest {
        val peer = ScriptedRobot().apply { answersHello = false }
        val e = assertFailsWith<ConnectFailedException> { connect(peer) }
        assertTrue("hello" in e.message!!, e.message)
        // A link that is up but never answers is a timeout, not a lost link: tools tell the two apart by the cause
        // (past the copies of the exception that coroutines' stack trace recovery may put in between).
        val timeout = assertIs<CommandTimeoutException>(generateSequence(e.cause) { it.cause }.firstOrNull { it !is ConnectFailedException })
        assertEquals("hello_request", timeout.command)
    }

    @Test
    fun theScopeThatMadeARobotWaitsForItsClose() = runTest {
        val peer = ScriptedRobot()
        lateinit var robot: Robot
        val closeAt = 5.seconds
        // The robot is a child of the scope: the scope returns only after the robot closed, and nothing is left.
        coroutineScope {
            robot = peer.device.connect(this + runtime(), testOptions())
            launch {
                delay(closeAt)
                assertEquals(ConnectionState.Connected, robot.connection.value)
                robot.close()
            }
        }
        assertTrue(currentTime >= closeAt.inWholeMilliseconds, "the scope returned at $currentTime ms, before the close")
        assertIs<ConnectionState.Closed>(robot.connection.value)
        assertTrue(!peer.connected)
    }

    @Test
    fun cancellingTheScopeClosesTheRobot() = runTest {
        val peer = ScriptedRobot()
        val connected = CompletableDeferred<Robot>()
        val scope = launch { connected.complete(peer.device.connect(this + runtime(), testOptions())) }
        val robot = connected.await()
        scope.cancel()
        scope.join()
        val closed = assertIs<ConnectionState.Closed>(robot.connection.value)
        assertTrue("scope" in closed.cause?.message.orEmpty(), "closed because: ${closed.cause}")
        assertTrue(!peer.connected)
        assertFailsWith<RobotClosedException> { robot.locomotion.enqueue(Movement.Straight(0.05, 0.1)) }
    }

    @Test
    fun connectingInAScopeThatEndedSaysSo() = runTest {
        val ended = CoroutineScope(Job().apply { cancel() } + runtime())
        val e = assertFailsWith<IllegalStateException> { ScriptedRobot().device.connect(ended, testOptions()) }
        assertTrue("scope has ended" in e.message!!, e.message)
    }

    @Test
    fun disconnectReturnsWhenEverythingTheRobotStartedHasEnded() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.disconnect()
        assertIs<ConnectionState.Closed>(robot.connection.value)
        assertTrue(!peer.connected)
    }

    @Test
    fun helloRequestIsRepeatedWhenTheFirstIsLost() = runTest {
        val peer = ScriptedRobot().apply { dropIncoming = 1 }
        val robot = connect(peer)
        assertEquals(ConnectionState.Connected, robot.connection.value)
        robot.close()
    }
}

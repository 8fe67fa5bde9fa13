package org.pocketbot.sdk

import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.SyncMode
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertIs
import kotlin.test.assertTrue

class ConnectTest {
    @Test
    fun handshakeLearnsIdentitySettingsAndStartsSync() = runTest {
        val peer = ScriptedRobot(robotId = 9, name = "Nine")
        peer.settings[70] = 0 // line_pid.kp low byte: a value only a real read can know
        val robot = connect(peer, testOptions(syncMode = SyncMode.FULL))
        assertEquals(ConnectionState.Connected, robot.connection.value)
        assertEquals(9, robot.identity.robotId)
        assertEquals("Nine", robot.identity.name)
        assertEquals("0.1.0", robot.identity.firmwareVersion)
        assertEquals(9, robot.settings.identity.robotId.value)
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
        val peer = ScriptedRobot(protocolVersion = 2, layoutHash = 0x12345678)
        val e = assertFailsWith<ProtocolMismatchException> { connect(peer) }
        assertTrue("v2" in e.message!! && "v${ProtocolInfo.VERSION}" in e.message!!, e.message)
        assertTrue("0x12345678" in e.message!!, e.message)
        assertEquals(2, e.robotVersion)
    }

    @Test
    fun layoutMismatchAloneFailsToo() = runTest {
        val peer = ScriptedRobot(layoutHash = ProtocolInfo.LAYOUT_HASH xor 1)
        assertFailsWith<ProtocolMismatchException> { connect(peer) }
    }

    @Test
    fun silentRobotFailsWithConnectFailed() = runTest {
        val peer = ScriptedRobot().apply { answersHello = false }
        val e = assertFailsWith<ConnectFailedException> { connect(peer) }
        assertTrue("hello" in e.message!!, e.message)
    }

    @Test
    fun secondConnectToKnownRobotSkipsTheSettingsRead() = runTest {
        val cache = InMemorySettingsCache()
        val peer = ScriptedRobot()
        connect(peer, testOptions(cache = cache)).apply {
            settings.linePid.kp.set(1.5f)
            close()
        }
        val again = connect(peer, testOptions(cache = cache))
        assertEquals(1, peer.executed.count { it is ReadSettings }, "the second connect read the settings again")
        assertEquals(1.5f, again.settings.linePid.kp.value)
        again.close()
    }

    @Test
    fun helloRequestIsRepeatedWhenTheFirstIsLost() = runTest {
        val peer = ScriptedRobot().apply { dropIncoming = 1 }
        val robot = connect(peer)
        assertEquals(ConnectionState.Connected, robot.connection.value)
        robot.close()
    }
}

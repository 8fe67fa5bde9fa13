package org.pocketbot.sdk

import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.ErrorCode
import org.pocketbot.protocol.LoadDefaults
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.SaveSettings
import org.pocketbot.protocol.UpdateSettings
import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertNotNull
import kotlin.test.assertTrue

class SettingsTest {
    @Test
    fun treeCoversEveryFieldOfTheProtocolOnce() = runTest {
        val robot = connect(ScriptedRobot())
        assertEquals(SETTINGS_FIELDS.map { it.path }, robot.settings.fields.map { it.path })
        assertEquals("line_pid.kp", robot.settings.linePid.kp.path)
        assertNotNull(robot.settings.field("geometry.wheel_base_m"))
        robot.close()
    }

    @Test
    fun writingOneFieldSendsOnlyThatFieldAndWaitsForTheAck() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.settings.linePid.kp.set(1.5f)
        val update = peer.executed.filterIsInstance<UpdateSettings>().single()
        assertEquals(70, update.offset)
        assertContentEquals(byteArrayOf(0, 0, 0xC0.toByte(), 0x3F), update.data)
        assertEquals(1.5f, robot.settings.linePid.kp.value)
        assertEquals(1.5f, robot.settings.values.value.linePid.kp)
        robot.close()
    }

    @Test
    fun everyKindOfFieldRoundTrips() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.settings.identity.name.set("Scout")
        robot.settings.encoder.pulsesPerRev.set(80)
        robot.settings.lineSensor.calMax.set(List(8) { 1000 + it })
        robot.settings.proximity.irPower.set(50)
        assertEquals("Scout", robot.settings.identity.name.value)
        assertEquals(80, robot.settings.encoder.pulsesPerRev.value)
        assertEquals(List(8) { 1000 + it }, robot.settings.lineSensor.calMax.value)
        assertEquals(50, robot.settings.proximity.irPower.value)
        assertEquals(4, peer.executed.count { it is UpdateSettings })
        robot.close()
    }

    @Test
    fun aRefusedValueThrowsTypedErrorAndKeepsTheOldValue() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val e = assertFailsWith<SettingRefusedException> { robot.settings.geometry.wheelBaseM.set(2.0f) }
        assertEquals("geometry.wheel_base_m", e.path)
        assertEquals(ErrorCode.SETTINGS_VALUE, e.code)
        assertEquals(2.0f, e.value)
        assertF32(0.026f, robot.settings.geometry.wheelBaseM.value)
        assertEquals(1, robot.linkStats.value.refused)
        robot.close()
    }

    @Test
    fun aValueThatCannotBeEncodedIsRejectedLocally() = runTest {
        val robot = connect(ScriptedRobot())
        assertFailsWith<IllegalArgumentException> { robot.settings.debug.level.set(300) }
        assertFailsWith<IllegalArgumentException> { robot.settings.identity.name.set("a name far too long") }
        robot.close()
    }

    @Test
    fun lostWriteIsRetransmittedWithTheSameSeqAndAppliedOnce() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.dropIncoming = 2
        robot.settings.linePid.kd.set(0.01f)
        assertEquals(1, peer.executed.count { it is UpdateSettings })
        assertF32(0.01f, robot.settings.linePid.kd.value)
        assertTrue(robot.linkStats.value.retransmissions >= 2)
        robot.close()
    }

    @Test
    fun lostAckLeadsToRetransmissionThatIsReAckedNotReExecuted() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.dropOutgoing = 1
        robot.settings.profile.accelMps2.set(2f)
        val sent = peer.received.filter { it.second is UpdateSettings }
        assertEquals(2, sent.size, "sent once, retransmitted once")
        assertEquals(sent[0].first, sent[1].first, "a retransmission keeps its sequence number")
        assertEquals(1, peer.executed.count { it is UpdateSettings })
        robot.close()
    }

    @Test
    fun noAckAtAllFailsWithTimeout() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, testOptions(commandRetries = 2))
        peer.dropIncoming = 100
        val e = assertFailsWith<CommandTimeoutException> { robot.settings.linePid.ki.set(1f) }
        assertEquals(3, e.attempts)
        robot.close()
    }

    @Test
    fun readAllSaveAndLoadDefaults() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.settings.linePid.kp.set(3f)
        peer.settings[159] = 100 // motors.pwm_limit changed behind our back
        peer.settings[160] = 0
        assertEquals(100, robot.settings.readAll().motors.pwmLimit)
        assertEquals(100, robot.settings.motors.pwmLimit.value)
        robot.settings.save()
        assertTrue(peer.executed.any { it == SaveSettings })
        robot.settings.loadDefaults()
        assertTrue(peer.executed.any { it == LoadDefaults })
        assertF32(0.0004f, robot.settings.linePid.kp.value)
        assertEquals(3, peer.executed.count { it is ReadSettings })
        robot.close()
    }

    @Test
    fun jsonExportImportRoundTripWritesOnlyWhatChanged() = runTest {
        val a = ScriptedRobot()
        val ra = connect(a)
        ra.settings.linePid.kp.set(1.25f)
        ra.settings.identity.name.set("Alpha")
        ra.settings.lineSensor.calMin.set(List(8) { 90 + it })
        val json = ra.settings.exportJson()
        assertTrue("\"line_pid\"" in json && "\"kp\"" in json, json)

        val b = ScriptedRobot(robotId = 8)
        val rb = connect(b)
        val written = rb.settings.importJson(json)
        // line_pid.kp, identity.name, line_sensor.cal_min and identity.robot_id (7 vs 8) differ
        assertEquals(4, written)
        assertEquals(1.25f, rb.settings.linePid.kp.value)
        assertEquals("Alpha", rb.settings.identity.name.value)
        assertEquals(List(8) { 90 + it }, rb.settings.lineSensor.calMin.value)
        assertContentEquals(a.settings, b.settings)
        assertEquals(0, rb.settings.importJson(json), "importing the same again changes nothing")
        ra.close(); rb.close()
    }

    @Test
    fun importRejectsUnknownFieldsAndWrongTypes() = runTest {
        val robot = connect(ScriptedRobot())
        assertFailsWith<IllegalArgumentException> { robot.settings.importJson("""{"line_pid": {"kq": 1}}""") }
        assertFailsWith<IllegalArgumentException> { robot.settings.importJson("""{"line_pid": {"kp": "fast"}}""") }
        assertFailsWith<IllegalArgumentException> { robot.settings.importJson("""{"line_pid": """) }
        robot.close()
    }
}

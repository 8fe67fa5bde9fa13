@file:OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)

package org.pocketbot.sdk

import kotlinx.coroutines.flow.first
import kotlinx.coroutines.test.advanceTimeBy
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.LoadDefaults
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.SaveSettings
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.UpdateSettings
import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertNotNull
import kotlin.test.assertSame
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

class SettingsTest {
    @Test
    fun treeCoversEveryFieldOfTheProtocolOnceUnderItsOneName() = runTest {
        val robot = connect(ScriptedRobot())
        assertEquals(SETTINGS_FIELDS.map { it.path }, robot.settings.fields.map { it.name })
        assertEquals("line_pid.kp", robot.settings.linePid.kp.name)
        assertSame(robot.settings.linePid.kp, robot.settings["line_pid.kp"])
        assertNotNull(robot.settings["geometry.wheel_base_m"])
        assertEquals("m", robot.settings.geometry.wheelBaseM.unit)
        assertEquals(0.005, robot.settings.geometry.wheelBaseM.min)
        robot.close()
    }

    @Test
    fun writingOneFieldSendsOnlyThatFieldAndWaitsForTheAck() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.settings.linePid.kp.set(1.5)
        val update = peer.executed.filterIsInstance<UpdateSettings>().single()
        assertEquals(offsetOf("line_pid.kp"), update.offset)
        assertContentEquals(byteArrayOf(0, 0, 0xC0.toByte(), 0x3F), update.data)
        assertEquals(1.5, robot.settings.linePid.kp.value)
        assertEquals(1.5, robot.settings.values.value[robot.settings.linePid.kp])
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
    fun settingsParseWhatPeopleType() = runTest {
        val robot = connect(ScriptedRobot())
        assertEquals(0.25, robot.settings.lineFollow.speedMps.parse(" 0.25 "))
        assertEquals(SyncMode.REDUCED, robot.settings.sync.mode.parse("reduced"))
        assertEquals(List(8) { it }, robot.settings.lineSensor.calMin.parse("[0, 1, 2, 3, 4, 5, 6, 7]"))
        assertFailsWith<IllegalArgumentException> { robot.settings.debug.level.parse("loud") }
        robot.close()
    }

    @Test
    fun aRefusedValueThrowsTypedErrorAndKeepsTheOldValue() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val e = assertFailsWith<SettingRefusedException> { robot.settings.geometry.wheelBaseM.set(2.0) }
        assertEquals("geometry.wheel_base_m", e.name)
        assertEquals(ErrorCode.SETTINGS_VALUE, e.code)
        assertEquals(2.0, e.value)
        assertF32(0.026f, robot.settings.geometry.wheelBaseM.value.toFloat())
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
        robot.settings.linePid.kd.set(0.01)
        assertEquals(1, peer.executed.count { it is UpdateSettings })
        assertF32(0.01f, robot.settings.linePid.kd.value.toFloat())
        assertTrue(robot.linkStats.value.retransmissions >= 2)
        robot.close()
    }

    @Test
    fun lostAckLeadsToRetransmissionThatIsReAckedNotReExecuted() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.dropOutgoing = 1
        robot.settings.profile.accelMps2.set(2.0)
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
        val e = assertFailsWith<CommandTimeoutException> { robot.settings.linePid.ki.set(1.0) }
        assertEquals(3, e.attempts)
        assertEquals("update_settings", e.command)
        robot.close()
    }

    @Test
    fun readAllSaveAndLoadDefaults() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.settings.linePid.kp.set(3.0)
        peer.poke("motors.pwm_limit", 100) // changed behind our back
        assertEquals(100, robot.settings.readAll()[robot.settings.motors.pwmLimit])
        assertEquals(100, robot.settings.motors.pwmLimit.value)
        robot.settings.save()
        assertTrue(peer.executed.any { it == SaveSettings })
        robot.settings.loadDefaults()
        assertTrue(peer.executed.any { it == LoadDefaults })
        assertF32(0.0004f, robot.settings.linePid.kp.value.toFloat())
        assertEquals(3, peer.executed.count { it is ReadSettings })
        robot.close()
    }

    @Test
    fun jsonExportImportRoundTripWritesOnlyWhatChanged() = runTest {
        val a = ScriptedRobot()
        val ra = connect(a)
        ra.settings.linePid.kp.set(1.25)
        ra.settings.identity.name.set("Alpha")
        ra.settings.lineSensor.calMin.set(List(8) { 90 + it })
        val json = ra.settings.exportJson()
        assertTrue("\"line_pid\"" in json && "\"kp\"" in json, json)

        val b = ScriptedRobot(robotId = 8)
        val rb = connect(b)
        val written = rb.settings.importJson(json)
        // line_pid.kp, identity.name, line_sensor.cal_min and identity.robot_id (7 vs 8) differ
        assertEquals(4, written)
        assertEquals(1.25, rb.settings.linePid.kp.value)
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

    @Test
    fun aRefusedImportNamesTheRefusedValue() = runTest {
        val robot = connect(ScriptedRobot())
        val e = assertFailsWith<SettingRefusedException> {
            robot.settings.importJson("""{"geometry": {"wheel_base_m": 3.0}}""")
        }
        assertEquals("geometry.wheel_base_m", e.name)
        assertEquals(3.0, e.value)
        assertTrue("geometry.wheel_base_m = 3" in e.message!!, e.message)
        robot.close()
    }

    @Test
    fun twoRobotsWithTheSameIdDoNotShareCachedSettings() = runTest {
        val cache = InMemorySettingsCache()
        // Every robot starts with id 1: two of them, at different addresses, with different settings.
        val a = ScriptedRobot(robotId = 1, address = "tcp://127.0.0.1:40001").apply { poke("line_pid.kp", 1.25) }
        val b = ScriptedRobot(robotId = 1, address = "tcp://127.0.0.1:40002").apply { poke("line_pid.kp", 2.5) }
        assertEquals(1.25, connect(a, testOptions(cache = cache)).settings.linePid.kp.value)
        assertEquals(2.5, connect(b, testOptions(cache = cache)).settings.linePid.kp.value)
        // Another robot at a's address later (a port reused): its checksum differs, so it is read, not taken from the cache.
        val c = ScriptedRobot(robotId = 1, address = "tcp://127.0.0.1:40001").apply { poke("line_pid.kp", 3.75) }
        assertEquals(3.75, connect(c, testOptions(cache = cache)).settings.linePid.kp.value)
        assertEquals(1, c.executed.count { it is ReadSettings })
    }

    @Test
    fun secondConnectToAnUnchangedRobotSkipsTheSettingsRead() = runTest {
        val cache = InMemorySettingsCache()
        val peer = ScriptedRobot()
        connect(peer, testOptions(cache = cache)).apply {
            settings.linePid.kp.set(1.5)
            close()
        }
        val again = connect(peer, testOptions(cache = cache))
        assertEquals(1, peer.executed.count { it is ReadSettings }, "the second connect read the settings again")
        assertEquals(1.5, again.settings.linePid.kp.value)
        again.close()
    }

    @Test
    fun aRobotResetMidSessionIsReadAgain() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, testOptions(syncMode = SyncMode.REDUCED))
        robot.settings.linePid.kp.set(1.5)
        // Power cycle: the robot comes back with what its EEPROM held, not with the write above.
        peer.poke("line_pid.kp", 0.5)
        peer.reset()
        runCurrent()
        robot.settings.linePid.kp.changes.first { it == 0.5 }
        assertEquals(2, peer.executed.count { it is ReadSettings })
        // ...and it gets the sync mode this host chose again.
        assertEquals(SetSync(SyncMode.REDUCED.code, 100), peer.executed.last { it is SetSync })
        robot.close()
    }

    @Test
    fun writingTheSyncModeSettingChangesTheReflectorToo() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, testOptions(syncMode = SyncMode.FULL))
        robot.settings.sync.mode.set(SyncMode.NONE)
        assertEquals(SyncMode.NONE, robot.reflector.mode.value)
        // With no state expected, the silence is no loss: the link stays up.
        advanceTimeBy(10.seconds)
        assertEquals(ConnectionState.Connected, robot.connection.value)
        assertEquals(0, robot.linkStats.value.reconnects)
        robot.settings.sync.periodMs.set(20)
        assertEquals(20.milliseconds, robot.reflector.period.value)
        robot.close()
    }
}

/** Settings as people read and type them, and as JSON files keep them: the faces' common vocabulary. */
class SettingsTextTest {
    @Test
    fun aFloatSettingReadsAsItsShortestDecimalAndAnEnumSettingByName() = runTest {
        val robot = connect(ScriptedRobot())
        robot.settings.linePid.kp.set(0.0004)
        assertEquals("0.0004", robot.settings.linePid.kp.valueText)
        assertEquals("line_pid.kp = 0.0004", robot.settings.linePid.kp.toString())
        robot.settings.track.speedMps.set(0.15)
        assertEquals("0.15", robot.settings.track.speedMps.valueText)
        assertEquals("0..100000", robot.settings.linePid.kp.rangeText)
        assertEquals("0.01..20", robot.settings.profile.accelMps2.rangeText)
        val mode = robot.settings.sync.mode
        assertEquals(listOf("none", "full", "reduced"), mode.names)
        assertEquals("none, full, reduced", mode.rangeText)
        assertEquals("none", mode.valueText)
        assertEquals(SyncMode.FULL, mode.parse(mode.format(SyncMode.FULL)))
        val refused = assertFailsWith<IllegalArgumentException> { mode.parse("1") }
        assertTrue("none, full, reduced" in refused.message!!, refused.message)
        assertEquals("", robot.settings.identity.name.rangeText)
        robot.close()
    }

    @Test
    fun aRefusalSaysWhatTheRobotAcceptsInWords() = runTest {
        val robot = connect(ScriptedRobot())
        val e = assertFailsWith<SettingRefusedException> { robot.settings.linePid.kp.set(-1.0) }
        assertEquals("robot refused line_pid.kp = -1: outside the range it accepts (0..100000)", e.message)
        robot.close()
    }

    @Test
    fun jsonKeepsFloatsExactAsShortDecimalsAndEnumsByName() = runTest {
        val robot = connect(ScriptedRobot())
        robot.settings.linePid.kp.set(0.0004)
        robot.settings.profile.accelMps2.set(0.15)
        val json = robot.settings.exportJson()
        assertTrue("\"kp\": 0.0004," in json, json)
        assertTrue("\"accel_mps2\": 0.15," in json, json)
        assertTrue("\"mode\": \"none\"," in json, json)
        assertTrue(!Regex("\\d[eE]-?\\d").containsMatchIn(json), "no exponent: $json")
        // Read back: the same floats, and an enumeration by name or by code.
        assertEquals(0, robot.settings.importJson(json))
        assertEquals(1, robot.settings.importJson("""{"sync": {"mode": "reduced"}}"""))
        assertEquals(SyncMode.REDUCED, robot.settings.sync.mode.value)
        assertEquals(1, robot.settings.importJson("""{"sync": {"mode": 1}}"""))
        assertEquals(SyncMode.FULL, robot.settings.sync.mode.value)
        val bad = assertFailsWith<IllegalArgumentException> { robot.settings.importJson("""{"sync": {"mode": "fast"}}""") }
        assertTrue("none, full, reduced" in bad.message!!, bad.message)
        robot.close()
    }
}

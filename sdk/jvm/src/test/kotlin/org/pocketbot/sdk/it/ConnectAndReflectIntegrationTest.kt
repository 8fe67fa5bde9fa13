package org.pocketbot.sdk.it

import kotlinx.coroutines.delay
import kotlinx.coroutines.async
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.RobotClosedException
import org.pocketbot.sdk.RobotOptions
import kotlin.test.assertNull
import kotlin.time.Duration.Companion.seconds
import kotlinx.coroutines.flow.filter
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.take
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.launch
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.link.LinkSettings
import org.pocketbot.sdk.ErrorCode
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.sdk.SyncMode
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.SettingRefusedException
import org.pocketbot.sdk.StateUpdate
import org.pocketbot.sdk.connect
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

/** Handshake, state and settings reflection against the real firmware in the emulator. */
class ConnectAndReflectIntegrationTest {
    @Test
    fun connectsAndLearnsIdentityAndSettings() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        assertEquals(ConnectionState.Connected, robot.connection.value)
        assertEquals(1, robot.identity.robotId)
        assertEquals(ProtocolInfo.LAYOUT_HASH, robot.identity.layoutHash)
        assertEquals(emu.handleOf(robot).name, robot.identity.name)
        assertMirrors(robot, emu.handleOf(robot).settingsBytes())
        robot.close()
    }

    @Test
    fun reportedStateWaitsForTheFirstFullStateAndFailsWhenTheRobotCloses() = withEmulator { emu ->
        val silent = RobotOptions { syncMode = SyncMode.NONE; settingsCache = InMemorySettingsCache() }
        val robot = connectAll(emu, silent).single()
        assertNull(withTimeoutOrNull(1.seconds) { robot.reportedState() }, "no state was sent, so none is reported")
        assertEquals(0, robot.state.value.power.batteryMv, "the mirror is all zero before the first state")

        robot.reflector.set(SyncMode.FULL, 50.milliseconds)
        val reported = robot.reportedState()
        assertTrue(reported.power.batteryMv > 3000, "battery of the reported state: ${reported.power.batteryMv} mV")
        assertTrue(reported.time.timeMs > 1000, "robot time of the reported state: ${reported.time.timeMs} ms")
        robot.close()

        val never = connectAll(emu, silent).single()
        val waiting = async { runCatching { never.reportedState() } }
        never.close()
        val failure = waiting.await().exceptionOrNull()
        assertTrue(failure is RobotClosedException, "waiting on a robot that closes must end with RobotClosedException: $failure")
    }

    @Test
    fun fullAndReducedStateUpdatesFlowWithRobotTime() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        robot.reflector.set(SyncMode.FULL, 20.milliseconds)
        val full = robot.stateUpdates.filter { it.kind == StateUpdate.Kind.FULL }.take(10).toList()
        val times = full.map { it.timeMs }
        assertTrue(times.zipWithNext().all { (a, b) -> b > a }, "robot time must increase: $times")
        // the first interval may still be on the old schedule
        assertTrue(times.drop(1).zipWithNext().all { (a, b) -> b - a in 15..60 }, "about 20 ms apart: $times")

        robot.reflector.set(SyncMode.REDUCED, 5.milliseconds)
        val reduced = robot.stateUpdates.filter { it.kind == StateUpdate.Kind.REDUCED }.take(20).toList()
        assertTrue(reduced.zipWithNext().all { (a, b) -> b.timeMs > a.timeMs })
        assertTrue(robot.linkStats.value.reducedStates >= 20)
        assertEquals(0, robot.linkStats.value.dropped)
        assertEquals(org.pocketbot.protocol.SyncMode.REDUCED.code, valueIn(emu.handleOf(robot).settingsBytes(), "sync.mode"), "settings.sync.mode on the robot")
        robot.close()
    }

    @Test
    fun settingWriteIsAppliedOnTheRobotAndRefusalIsTyped() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        robot.settings.linePid.kp.set(1.5)
        assertEquals(1.5, robot.settings.linePid.kp.value)
        val onRobot = sim.settingsBytes()
        assertEquals(1.5, valueIn(onRobot, "line_pid.kp"))

        val e = assertFailsWith<SettingRefusedException> { robot.settings.geometry.wheelBaseM.set(2.0) }
        assertEquals(ErrorCode.SETTINGS_VALUE, e.code)
        assertEquals(0.026f.toDouble(), robot.settings.geometry.wheelBaseM.value)
        assertContentEquals(onRobot, sim.settingsBytes(), "a refused write must not change the robot")

        robot.settings.identity.name.set("Hello")
        assertEquals("Hello", sim.name)
        assertEquals(robot.settings.values.value, robot.settings.readAll())
        robot.close()
    }

    @Test
    fun jsonExportImportAcrossTwoRobots() = withEmulator(robots = 2) { emu ->
        val (a, b) = connectAll(emu)
        a.settings.lineFollow.speedMps.set(0.3)
        a.settings.proximity.holdMs.set(500)
        val written = b.settings.importJson(a.settings.exportJson())
        assertTrue(written >= 2, "robot_id and name differ too: $written")
        assertEquals(0.3f.toDouble(), b.settings.lineFollow.speedMps.value)
        assertContentEquals(emu.handleOf(a).settingsBytes(), emu.handleOf(b).settingsBytes())
        a.close(); b.close()
    }

    @Test
    fun corruptionAndLossAreCountedAndNeverReachTheState() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        robot.reflector.set(SyncMode.FULL, 10.milliseconds)
        sim.link = LinkSettings(corruptionRate = 0.003, lossRate = 0.002)
        var insane = 0
        val watcher = launch {
            robot.stateUpdates.collect { u ->
                // A corrupted state that slipped through would show wild values somewhere.
                if (u.state.power.batteryMv !in 2500..5000 || u.state.time.timeMs > 1_000_000) insane++
            }
        }
        robot.settings.linePid.kd.set(0.003) // commands still get through, retransmitted as needed
        delay(2000)
        watcher.cancel()
        sim.link = LinkSettings()
        val stats = robot.linkStats.value
        assertTrue(stats.dropped > 0, "some frames must have been dropped: $stats")
        assertTrue(stats.fullStates > 100, "states keep flowing: $stats")
        assertEquals(0, insane, "a corrupted state was applied")
        assertEquals(0.003f.toDouble(), robot.settings.linePid.kd.value)
        robot.close()
    }

    @Test
    fun secondConnectSkipsTheSettingsRead() = withEmulator { emu ->
        val cache = org.pocketbot.sdk.InMemorySettingsCache()
        val device = emu.discoverer().discover().first()
        val t0 = emu.time
        device.connect(this, RobotOptions(itOptions()) { settingsCache = cache }).disconnect()
        val first = emu.time - t0
        val t1 = emu.time
        val again = device.connect(this, RobotOptions(itOptions()) { settingsCache = cache })
        val second = emu.time - t1
        assertMirrors(again, emu.robots.single().settingsBytes())
        // Simulated time: the settings read is about 200 bytes at 115200 Bd, some 20 ms of link time.
        assertTrue(second < first, "cached connect ($second) should beat the first ($first)")
        again.close()
    }

    @Test
    fun twoRobotsWithTheSameIdKeepTheirOwnSettings() = withEmulator(robots = 2) { emu ->
        val cache = org.pocketbot.sdk.InMemorySettingsCache()
        val (a, b) = connectAll(emu, RobotOptions(itOptions()) { settingsCache = cache })
        b.settings.identity.robotId.set(1) // both are robot 1 now, as every fresh robot is
        a.settings.linePid.kp.set(1.25)
        b.settings.linePid.kp.set(2.5)
        a.disconnect()
        b.disconnect()
        val (a2, b2) = connectAll(emu, RobotOptions(itOptions()) { settingsCache = cache })
        assertEquals(1, a2.identity.robotId)
        assertEquals(1, b2.identity.robotId)
        assertEquals(1.25, a2.settings.linePid.kp.value)
        assertEquals(2.5, b2.settings.linePid.kp.value)
        assertMirrors(b2, emu.handleOf(b2).settingsBytes())
        a2.close(); b2.close()
    }

    @Test
    fun aRobotResetMidSessionIsReadAgain() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        robot.settings.linePid.kp.set(1.25)
        robot.settings.save()
        robot.settings.linePid.kp.set(2.5) // not saved: a reset forgets it
        sim.reset()
        robot.settings.linePid.kp.changes.first { it == 1.25 }
        assertMirrors(robot, sim.settingsBytes())
        robot.close()
    }

    @Test
    fun syncModeWrittenAsASettingIsTheReflectorsToo() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        robot.settings.sync.mode.set(SyncMode.NONE)
        assertEquals(SyncMode.NONE, robot.reflector.mode.value)
        delay(10_000)
        assertEquals(ConnectionState.Connected, robot.connection.value, "no state is expected: silence is no loss")
        assertEquals(0, robot.linkStats.value.reconnects)
        robot.close()
    }
}

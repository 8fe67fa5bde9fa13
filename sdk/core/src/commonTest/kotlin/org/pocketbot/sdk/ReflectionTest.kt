@file:OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)

package org.pocketbot.sdk

import kotlinx.coroutines.flow.first
import kotlinx.coroutines.launch
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Heartbeat
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.StateEncoders
import org.pocketbot.protocol.StateFull
import org.pocketbot.protocol.StateReduced
import org.pocketbot.protocol.StateTime
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

class ReflectionTest {
    @Test
    fun fullStateIsVisibleWithItsRobotTime() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val s = WIRE_EMPTY.with(time = StateTime(1234, 0, 0, 0), encoders = StateEncoders(10, 20))
        peer.sendState(s)
        val seen = robot.state.first { it.time.timeMs == 1234L }
        assertEquals(StateEncoders(10, 20).toModel(), seen.encoders)
        assertEquals(1, robot.linkStats.value.fullStates)
        robot.close()
    }

    @Test
    fun reducedStateUpdatesOnlyItsPart() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val full = WIRE_EMPTY.with(time = StateTime(100, 0, 0, 0), power = org.pocketbot.protocol.StatePower(3700, 0, 0))
        peer.sendState(full)
        robot.state.first { it.time.timeMs == 100L }
        peer.sendReduced(StateReduced(105, 3, 4, 50, 60, -200, 1))
        val merged = robot.state.first { it.time.timeMs == 105L }
        assertEquals(StateEncoders(3, 4).toModel(), merged.encoders)
        assertEquals(50, merged.wheels.speedLeftMmps)
        assertEquals(-200, merged.line.position)
        assertEquals(3700, merged.power.batteryMv, "a reduced packet must keep the rest of the state")
        assertEquals(-200, robot.lineSensor.positionPermille)
        assertEquals(1, robot.linkStats.value.reducedStates)
        robot.close()
    }

    @Test
    fun everyUpdateIsInStateUpdates() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val kinds = mutableListOf<StateUpdate.Kind>()
        val job = launch { robot.stateUpdates.collect { kinds += it.kind } }
        runCurrent()
        peer.sendState(WIRE_EMPTY.with(time = StateTime(1, 0, 0, 0)))
        peer.sendState(WIRE_EMPTY.with(time = StateTime(1, 0, 0, 0))) // identical: a StateFlow would drop it
        peer.sendReduced(StateReduced(2, 0, 0, 0, 0, 0, 0))
        robot.state.first { it.time.timeMs == 2L }
        runCurrent()
        assertEquals(listOf(StateUpdate.Kind.FULL, StateUpdate.Kind.FULL, StateUpdate.Kind.REDUCED), kinds)
        job.cancel()
        robot.close()
    }

    @Test
    fun corruptTruncatedAndUnknownFramesAreCountedAndNeverApplied() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val good = Frames.encode(StateFull(WIRE_EMPTY.with(time = StateTime(77, 0, 0, 0))), 0)
        peer.sendRaw(good.copyOf().also { it[10] = (it[10] + 1).toByte() })         // bit error
        peer.sendRaw(good.copyOf(good.size - 7))                                      // truncated
        peer.sendRaw(byteArrayOf(0x7F, 0, 0) + crcOf(byteArrayOf(0x7F, 0, 0)))          // unknown type
        peer.sendRaw(byteArrayOf(1))                                                    // too short
        peer.sendState(WIRE_EMPTY.with(time = StateTime(78, 0, 0, 0)))
        robot.state.first { it.time.timeMs == 78L }
        val stats = robot.linkStats.value
        assertEquals(1, stats.badCrc)
        assertEquals(1, stats.badLength)
        assertEquals(1, stats.unknownType)
        assertEquals(1, stats.tooShort)
        assertEquals(4, stats.dropped)
        assertEquals(1, stats.fullStates, "only the good state may be applied")
        assertTrue(robot.debugLog.messages.replayCache.any { "bad_crc" in it.text })
        robot.close()
    }

    @Test
    fun reflectorSendsModeAndPeriodAndKeepsThemInSettings() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.reflector.set(SyncMode.REDUCED, 5.milliseconds)
        assertEquals(2, peer.syncMode)
        assertEquals(5, peer.syncPeriodMs)
        assertEquals(SyncMode.REDUCED, robot.reflector.mode.value)
        assertEquals(SyncMode.REDUCED, robot.settings.sync.mode.value)
        assertEquals(5, robot.settings.sync.periodMs.value)
        assertEquals(SetSync(2, 5), peer.executed.last())
        robot.close()
    }

    @Test
    fun heartbeatsKeepTheFailsafeQuiet() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.settings.link.failsafeTimeoutMs.set(300)
        val before = peer.received.count { it.second == Heartbeat }
        kotlinx.coroutines.delay(1.seconds)
        val beats = peer.received.count { it.second == Heartbeat } - before
        assertTrue(beats in 8..12, "expected a heartbeat about every 100 ms, got $beats in 1 s")
        robot.close()
    }

    @Test
    fun silenceWhileSyncingMeansLinkLost() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, testOptions(syncMode = SyncMode.FULL))
        val lost = robot.connection.first { it is ConnectionState.Lost }
        assertTrue("nothing received" in (lost as ConnectionState.Lost).reason, lost.reason)
        robot.close()
    }

    private fun crcOf(b: ByteArray): ByteArray {
        val c = org.pocketbot.protocol.Crc16.compute(b)
        return byteArrayOf(c.toByte(), (c shr 8).toByte())
    }
}

@file:OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)

package org.pocketbot.sdk

import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.StateReduced
import org.pocketbot.protocol.StateTime
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

/** Robot.freshness says which values of the state are live, and why and since when the others are not. */
class FreshnessTest {
    private fun ScriptedRobot.stateAt(ms: Long) = sendState(WIRE_EMPTY.with(time = StateTime(ms, 0, 0, 0)))

    @Test
    fun valuesAreLiveWhileStatesComeAndStaleWithTheirAgeOnceTheRobotFallsSilentOrTheLinkGoes() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, testOptions(syncMode = SyncMode.FULL))
        assertEquals(StaleReason.NOT_YET, robot.freshness.value.full.staleBecause, "no state yet")
        peer.stateAt(100)
        runCurrent()
        assertTrue(robot.freshness.value.full.isLive && robot.freshness.value.reduced.isLive, "${robot.freshness.value}")
        assertNull(robot.freshness.value.full.age())
        // Five periods without a state (the link itself is given 2 s of silence): stale, from robot time 100 ms.
        delay(1000.milliseconds)
        val silent = robot.freshness.value.full
        assertEquals(StaleReason.SILENT, silent.staleBecause, "$silent")
        assertEquals(100L, silent.robotTimeMs)
        assertNotNull(silent.age())
        peer.stateAt(900)
        runCurrent()
        assertTrue(robot.freshness.value.full.isLive, "live again with the next state")

        peer.stateAt(1000)
        runCurrent()
        peer.disconnect()
        val down = robot.freshness.first { !it.full.isLive }
        assertEquals(StaleReason.LINK_DOWN, down.full.staleBecause)
        assertEquals(StaleReason.LINK_DOWN, down.reduced.staleBecause)
        assertEquals(1000L, down.full.robotTimeMs, "the values date from the last state heard")
        // Back, but nothing heard yet: still not live, whatever the old values say.
        awaitReconnect(robot)
        runCurrent()
        assertEquals(StaleReason.NOT_YET, robot.freshness.value.full.staleBecause)
        assertEquals(1000L, robot.freshness.value.full.robotTimeMs)
        peer.stateAt(1200)
        runCurrent()
        assertTrue(robot.freshness.value.full.isLive)
        robot.close()
    }

    @Test
    fun inReducedSyncOnlyWhatReducedStatesCarryIsLive() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, testOptions(syncMode = SyncMode.FULL))
        peer.stateAt(500)
        runCurrent()
        robot.reflector.set(SyncMode.REDUCED, 4.milliseconds)
        peer.sendReduced(StateReduced(510, 0, 0, 0, 0, 0, 0))
        runCurrent()
        val f = robot.freshness.value
        assertEquals(StaleReason.NOT_SENT, f.full.staleBecause, "$f")
        assertEquals(500L, f.full.robotTimeMs, "from the last full state")
        assertTrue(f.reduced.isLive, "$f")
        robot.reflector.set(SyncMode.NONE)
        runCurrent()
        assertEquals(StaleReason.NOT_SENT, robot.freshness.value.reduced.staleBecause)
        assertEquals(510L, robot.freshness.value.reduced.robotTimeMs)
        robot.close()
    }
}

package org.pocketbot.sdk

import kotlinx.coroutines.test.runTest
import org.pocketbot.sdk.transport.LinkRate
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.time.Duration.Companion.milliseconds

/** The tuner samples as fast as the robot's link carries reduced states, with room left for commands. */
class TunerTest {
    @Test
    fun onThePocketBotsSerialLinkTheTunerSamplesEvery4Ms() = runTest {
        val peer = ScriptedRobot()
        val tuner = Tuner(connect(peer))
        assertEquals(4.milliseconds, tuner.samplePeriod)
        tuner.begin()
        assertEquals(SyncMode.REDUCED.code to 4, peer.syncMode to peer.syncPeriodMs, "the robot was asked for reduced state every 4 ms")
        tuner.end()
        assertEquals(SyncMode.NONE.code, peer.syncMode, "the sync mode before tuning is given back")
    }

    @Test
    fun aSlowerLinkGetsALongerPeriodAndAFasterOneAShorterOne() = runTest {
        // A 26-byte reduced frame at 38400 Bd takes 6.8 ms: 60 % of the link is one every 11.3 ms, so 12 ms.
        val slow = ScriptedRobot().apply { linkRate = LinkRate.ofBaud(38_400) }
        assertEquals(12.milliseconds, Tuner(connect(slow)).samplePeriod)
        // At 1 Mbit/s a frame takes 0.26 ms: the period cannot go below the robot's 1 ms.
        val fast = ScriptedRobot(robotId = 8).apply { linkRate = LinkRate.ofBaud(1_000_000) }
        assertEquals(1.milliseconds, Tuner(connect(fast)).samplePeriod)
    }
}

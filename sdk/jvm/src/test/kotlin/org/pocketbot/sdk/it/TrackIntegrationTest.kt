package org.pocketbot.sdk.it

import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import org.junit.jupiter.api.Test
import org.pocketbot.sdk.LocoMode
import org.pocketbot.sdk.SettingRefusedException
import org.pocketbot.sdk.TrackStatus
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue

/** The SDK's handle on the firmware's track behaviour (thesis A.3): start, speed, stop, and a motion command ending it. */
class TrackIntegrationTest {
    @Test
    fun startSetSpeedAndStopTheTrackBehaviour() = withEmulator(world = "round") { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        // Robot 1 creates the token and would drive faster with it: no boost, so that it drives the cruise speed.
        robot.settings.track.tokenBoostPercent.set(0)
        robot.track.start()
        robot.state.first { it.track.status == TrackStatus.FOLLOWING }
        assertTrue(robot.track.holdsToken, "robot 1 created the token")
        assertEquals(LocoMode.TRACK, robot.state.value.locomotion.mode)

        robot.track.setSpeed(0.2)
        assertEquals(0.2, robot.settings.track.speedMps.value, 1e-6)
        delay(1000) // up to speed
        val before = sim.trueWheelDistances
        delay(1000)
        val after = sim.trueWheelDistances
        val driven = (after.leftM - before.leftM + after.rightM - before.rightM) / 2
        assertTrue(driven in 0.17..0.23, "drove $driven m in 1 s at 0.2 m/s")
        assertFailsWith<SettingRefusedException> { robot.track.setSpeed(0.5) }
        assertEquals(0.2, robot.settings.track.speedMps.value, 1e-6, "a refused speed changes nothing")

        robot.track.stop()
        robot.state.first { it.track.status == TrackStatus.OFF && it.wheels.speedLeftMmps == 0 && it.wheels.speedRightMmps == 0 }
        assertEquals(TrackStatus.OFF, robot.track.status)

        robot.track.start()
        robot.state.first { it.track.status == TrackStatus.FOLLOWING }
        robot.locomotion.stop()
        robot.state.first { it.track.status == TrackStatus.OFF }
        assertTrue(robot.state.value.locomotion.mode != LocoMode.TRACK, "a motion command ends the behaviour")
        robot.close()
    }
}

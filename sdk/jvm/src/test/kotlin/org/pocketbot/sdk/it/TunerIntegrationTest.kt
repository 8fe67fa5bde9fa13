package org.pocketbot.sdk.it

import org.junit.jupiter.api.Test
import org.pocketbot.emulator.link.LinkSettings
import org.pocketbot.sdk.Controller
import org.pocketbot.sdk.StepSize
import org.pocketbot.sdk.SyncMode
import org.pocketbot.sdk.Tuner
import kotlin.test.assertEquals
import kotlin.test.assertNotNull
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds

/** PID tuning on the real firmware: fast reduced samples, a step test's response, the sync mode given back. */
class TunerIntegrationTest {
    @Test
    fun aWheelSpeedStepTestCapturesEverySampleOfTheResponse() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val tuner = Tuner(robot)
        tuner.begin()
        assertEquals(SyncMode.REDUCED, robot.reflector.mode.value)
        val response = tuner.stepTest(Controller.WHEEL_SPEED)
        tuner.end()
        assertEquals(SyncMode.FULL, robot.reflector.mode.value, "the robot's sync mode is given back")

        val samples = response.samples
        // 1 s of step and 0.4 s of settling at one sample every 4 ms: about 350, none missing.
        assertTrue(samples.size in 330..380, "${samples.size} samples")
        val gaps = samples.zipWithNext { a, b -> b.timeMs - a.timeMs }
        assertEquals(4L, tuner.samplePeriod.inWholeMilliseconds, "the emulated 115200 Bd link carries a reduced state every 4 ms")
        assertTrue(gaps.all { it == tuner.samplePeriod.inWholeMilliseconds }, "gaps between samples: ${gaps.toSet()}")
        assertEquals(0.15, response.step)
        assertTrue(samples.count { it.setpoint == 0.15 } > 200, "the step's setpoint is on the samples")
        val rise = assertNotNull(response.riseTimeMs, "the wheel reached 90 % of its step")
        assertTrue(rise in 1..500, "rise time $rise ms")
        assertTrue(response.overshootPercent!! < 50, "overshoot ${response.overshootPercent} %")
        assertTrue(samples.last().measured < 0.02, "the wheel stopped after the step: ${samples.last()}")
        assertEquals(listOf(robot.settings.wheelPid.kp.value, robot.settings.wheelPid.ki.value, robot.settings.wheelPid.kd.value), response.gains)
        assertTrue(response.toCsv().lines().first() == "time_ms,setpoint,measured")
        robot.close()
    }

    @Test
    fun aRobotSpeedStepTestDrivesItsManoeuvreAndMeasuresTheMeanWheelSpeed() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val tuner = Tuner(robot)
        tuner.begin()
        val response = tuner.stepTest(Controller.ROBOT_SPEED)
        tuner.end()
        val top = response.samples.maxOf { it.measured }
        assertTrue(top in 0.17..0.25, "cruise at 0.2 m/s, measured up to $top")
        val driven = emu.handleOf(robot).trueWheelDistances.let { (it.leftM + it.rightM) / 2 }
        assertTrue(driven in 0.28..0.32, "the manoeuvre is 30 cm, drove $driven m")
        robot.close()
    }

    @Test
    fun aRobotSpeedStepOfChosenSizeHasTheSetpointOfTheProfileTheRobotBrakesOn() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val tuner = Tuner(robot)
        tuner.begin()
        val size = StepSize(speedMps = 0.15, distanceM = 0.2, duration = 1.seconds)
        assertEquals("drives 0.2 m straight ahead at 0.15 m/s", size.describe(Controller.ROBOT_SPEED))
        val response = tuner.stepTest(Controller.ROBOT_SPEED, size)
        tuner.end()
        val driven = emu.handleOf(robot).trueWheelDistances.let { (it.leftM + it.rightM) / 2 }
        assertTrue(driven in 0.18..0.22, "the step is 20 cm, drove $driven m")
        val held = response.samples.filter { it.setpoint != 0.0 }
        assertEquals(0.15, held.maxOf { it.setpoint }, 1e-9, "the profile cruises at the step's speed")
        // The profile starts slow and brakes towards the end: the setpoint says so, as the robot's speed does.
        assertTrue(held.first().setpoint < 0.05, "starts at the profile's minimum speed: ${held.first()}")
        val braking = held.drop(held.indexOfLast { it.setpoint == 0.15 })
        assertTrue(braking.last().setpoint < 0.06, "brakes to the profile's minimum speed: ${braking.map { it.setpoint }}")
        assertTrue(braking.zipWithNext().all { (a, b) -> b.setpoint <= a.setpoint }, "and never speeds up again: ${braking.map { it.setpoint }}")
        assertTrue(response.rmsError < 0.03, "a setpoint the robot follows: rms error ${response.rmsError} m/s")
        robot.close()
    }

    @Test
    fun aSlowerLinkIsSampledAsFastAsItCarriesAndNoFaster() = withEmulator { emu ->
        emu.robot(1).link = LinkSettings(baud = 38_400)
        val robot = connectAll(emu).single()
        val tuner = Tuner(robot)
        assertEquals(12L, tuner.samplePeriod.inWholeMilliseconds, "26-byte frames at 3840 bytes/s, 60 % of the link")
        val droppedBefore = emu.handleOf(robot).state().errors.txDropped
        tuner.begin()
        val response = tuner.stepTest(Controller.WHEEL_SPEED)
        tuner.end()
        val gaps = response.samples.zipWithNext { a, b -> b.timeMs - a.timeMs }
        assertTrue(gaps.isNotEmpty() && gaps.all { it == 12L }, "gaps between samples: ${gaps.toSet()}")
        assertEquals(droppedBefore, emu.handleOf(robot).state().errors.txDropped, "the robot dropped no packet while tuned")
        robot.close()
    }
}

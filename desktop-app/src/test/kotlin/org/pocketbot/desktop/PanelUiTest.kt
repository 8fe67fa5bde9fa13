package org.pocketbot.desktop

import androidx.compose.ui.test.ExperimentalTestApi
import androidx.compose.ui.test.onNodeWithTag
import androidx.compose.ui.input.key.Key
import androidx.compose.ui.test.performClick
import androidx.compose.ui.test.performKeyInput
import androidx.compose.ui.test.performScrollToKey
import androidx.compose.ui.test.performTextReplacement
import androidx.compose.ui.test.runComposeUiTest
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.sdk.Controller
import org.pocketbot.sdk.LocoMode
import org.pocketbot.sdk.SyncMode
import kotlin.math.abs
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/**
 * The panel as people use it: clicks and typing in the real composables, against the embedded emulator running the
 * real firmware. The waits are liveness guards (how long a loaded CI machine may take), not timing assertions.
 */
@OptIn(ExperimentalTestApi::class)
class PanelUiTest {
    private val guard = GUARD_MS

    @Test
    fun lineSensorBarsChangeWhileTheRobotFollowsTheTape() = PanelFixture().use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            connectRobot(f)
            onNodeWithTag("tab-COMMANDS").performClick()
            onNodeWithTag("follow-start").performClick()
            waitUntil(timeoutMillis = guard) { f.panel.selected.value!!.robot.state.value.locomotion.mode == LocoMode.LINE_FOLLOW }
            onNodeWithTag("tab-SENSORS").performClick()
            val seen = mutableSetOf<String>()
            waitUntil(timeoutMillis = guard) {
                seen += onNodeWithTag("line-bars").description()
                seen.size >= 5
            }
            assertTrue(onNodeWithTag("line-status").text().contains("line seen"), onNodeWithTag("line-status").text())
            assertEquals("line_follow", onNodeWithTag("loco-mode").text())
        }
    }

    @Test
    fun aSettingIsWrittenAcknowledgedAndReadBackAndAnOutOfRangeValueIsRefused() = PanelFixture().use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            connectRobot(f)
            onNodeWithTag("tab-SETTINGS").performClick()
            onNodeWithTag("settings-list").performScrollToKey("line_pid.kp")
            onNodeWithTag("setting-line_pid.kp").performTextReplacement("0.75")
            onNodeWithTag("write-line_pid.kp").performClick()
            waitUntil(timeoutMillis = guard) { onNodeWithTag("status-line_pid.kp").text().startsWith("acknowledged") }
            assertEquals(0.75f, f.robotFloat("line_pid.kp"), "the robot holds the new value")

            onNodeWithTag("setting-line_pid.kp").performTextReplacement("-5")
            onNodeWithTag("write-line_pid.kp").performClick()
            waitUntil(timeoutMillis = guard) { onNodeWithTag("status-line_pid.kp").text().startsWith("refused") }
            assertTrue(onNodeWithTag("status-line_pid.kp").text().contains("outside the range"), onNodeWithTag("status-line_pid.kp").text())
            assertEquals(0.75f, f.robotFloat("line_pid.kp"), "a refused value leaves the robot's setting as it was")

            // Read all: the panel shows what the robot holds, not what was typed.
            onNodeWithTag("settings-read").performClick()
            waitUntil(timeoutMillis = guard) { onNodeWithTag("setting-line_pid.kp").text() == "0.75" }
        }
    }

    @Test
    fun aQueuedMovementFinishesAndTheTrajectoryGrowsByItsLength() = PanelFixture().use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            val robot = connectRobot(f)
            val before = robot.robot.odometry.trajectory.lengthM
            onNodeWithTag("tab-COMMANDS").performClick()
            onNodeWithTag("move-amount").performTextReplacement("0.15")
            onNodeWithTag("enqueue").performClick()
            waitUntil(timeoutMillis = guard) { robot.movements.value.isNotEmpty() }
            val id = robot.movements.value.single().handle.id
            waitUntil(timeoutMillis = guard) { onNodeWithTag("result-$id").text().startsWith("finished") }
            val grown = robot.robot.odometry.trajectory.lengthM - before
            assertTrue(abs(grown - 0.15) < 0.02, "the odometry path grew by $grown m for a 0.15 m movement")
            onNodeWithTag("tab-TRAJECTORY").performClick()
            waitUntil(timeoutMillis = guard) { onNodeWithTag("trajectory-lengths").text().contains("PocketBot-1 0.1") }
        }
    }

    @Test
    fun keysOnTheDrivePadDriveTheRobotAndReleasingThemStopsIt() = PanelFixture(world = "straight").use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            connectRobot(f)
            val wheels = { f.panel.selected.value!!.robot.state.value.wheels }
            onNodeWithTag("tab-COMMANDS").performClick()
            onNodeWithTag("drive-pad").performClick() // focus, as a click does
            onNodeWithTag("drive-pad").performKeyInput { keyDown(Key.W) }
            waitUntil(timeoutMillis = guard) { wheels().speedLeftMmps > 100 && wheels().speedRightMmps > 100 }
            onNodeWithTag("drive-pad").performKeyInput { keyUp(Key.W) }
            waitUntil(timeoutMillis = guard) { wheels().speedLeftMmps == 0 && wheels().speedRightMmps == 0 }
        }
    }

    @Test
    fun theTuningChartReceivesEveryReducedStateSampleAndTheGainsStepFreezeAndOverlay() = PanelFixture().use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            val robot = connectRobot(f)
            onNodeWithTag("tab-TUNING").performClick()
            onNodeWithTag("controller-WHEEL_SPEED").performClick()
            onNodeWithTag("tuning-start").performClick()
            waitUntil(timeoutMillis = guard) { robot.robot.reflector.mode.value == SyncMode.REDUCED }
            onNodeWithTag("step-test").performClick()
            onNodeWithTag("step-confirm").performClick()
            waitUntil(timeoutMillis = guard) { robot.tuning.captured != null }
            val live = robot.tuning.live.snapshot()
            assertTrue(live.size > 300, "only ${live.size} samples")
            // Reduced state comes every sample period of robot time: a gap means a sample never reached the chart.
            val period = robot.tuning.samplePeriod.inWholeMilliseconds
            assertEquals(4L, period, "the emulated 115200 Bd link carries a reduced state every 4 ms")
            val gaps = live.zipWithNext { a, b -> b.timeMs - a.timeMs }.filter { it > period }
            assertTrue(gaps.isEmpty(), "samples missing from the chart: gaps of $gaps ms")
            val charted = robot.tuning.live.added.get()
            val sent = robot.robot.linkStats.value.reducedStates - robot.tuning.reducedAtStart
            assertTrue(sent - charted in 0..2, "charted $charted of $sent reduced states") // the newest may still be on its way
            val first = robot.tuning.captured!!
            assertTrue(first.samples.maxOf { it.measured } > 0.12, "the wheel did not reach its step: $first")
            waitUntil(timeoutMillis = guard) { onNodeWithTag("step-figures").text().contains("rise") }

            // +: the gain times 1.25, written to the robot; -: times 0.8.
            val kp = robot.robot.settings.wheelPid.kp.value
            onNodeWithTag("gain-up-kp").performClick()
            waitUntil(timeoutMillis = guard) { abs(robot.robot.settings.wheelPid.kp.value - kp * 1.25) < 1e-4 * kp }
            assertEquals((kp * 1.25).toFloat(), f.robotFloat("wheel_pid.kp"), 1e-4f * kp.toFloat(), "the robot holds the stepped gain")
            onNodeWithTag("gain-down-kp").performClick()
            waitUntil(timeoutMillis = guard) { abs(robot.robot.settings.wheelPid.kp.value - kp) < 1e-4 * kp }

            // Freeze the first run as the reference: the next run is drawn over it.
            onNodeWithTag("tuning-freeze").performClick()
            onNodeWithTag("step-test").performClick()
            onNodeWithTag("step-confirm").performClick()
            waitUntil(timeoutMillis = guard) { robot.tuning.captured !== first && robot.tuning.running.value.not() }
            assertTrue(robot.tuning.capturesOf(Controller.WHEEL_SPEED).reference === first, "the frozen run stays the reference")
            waitUntil(timeoutMillis = guard) { onNodeWithTag("step-chart").description().contains("reference measured") }
            assertTrue(onNodeWithTag("step-chart").description().contains("this run measured"), onNodeWithTag("step-chart").description())

            onNodeWithTag("tuning-stop").performClick()
            waitUntil(timeoutMillis = guard) { robot.robot.reflector.mode.value == SyncMode.FULL }
            onNodeWithTag("tab-SENSORS").performClick()
            waitUntil(timeoutMillis = guard) { !exists("stale-banner") }
            assertTrue(!onNodeWithTag("loco-mode").isStale(), "live again in full sync")
        }
    }
}

package org.pocketbot.desktop

import androidx.compose.ui.test.ExperimentalTestApi
import androidx.compose.ui.test.hasTestTag
import androidx.compose.ui.test.hasText
import androidx.compose.ui.test.onNodeWithTag
import androidx.compose.ui.test.performClick
import androidx.compose.ui.test.performScrollToKey
import androidx.compose.ui.test.performTextReplacement
import androidx.compose.ui.test.runComposeUiTest
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.LocoMode
import org.pocketbot.sdk.SyncMode
import kotlin.math.abs
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/**
 * Issue 21 as a user of the panel meets it, against the embedded emulator running the real firmware: values of a
 * robot that went away, numbers people read, the step test, a movement over line following, a form that keeps what
 * was typed, and a console that does not drown in repeated failures.
 */
@OptIn(ExperimentalTestApi::class)
class PanelTruthUiTest {
    private val ago = Regex("""\b\d+ s ago\b""")

    @Test
    fun aRobotWhoseLinkDiedShowsEveryValueStaleWithItsAgeInEveryView() = PanelFixture(world = "straight").use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            val robot = connectRobot(f)
            onNodeWithTag("tab-COMMANDS").performClick()
            onNodeWithTag("move-amount").performTextReplacement("1.0")
            onNodeWithTag("move-speed").performTextReplacement("0.1")
            onNodeWithTag("enqueue").performClick()
            await("the movement runs") { robot.movements.value.isNotEmpty() && robot.robot.state.value.wheels.speedLeftMmps > 50 }
            val id = robot.movements.value.single().handle.id
            await("the running movement says so", { onNodeWithTag("result-$id").text() }) { onNodeWithTag("result-$id").text() == "running" }

            robot.emulated!!.disconnectLink() // the robot is gone: nothing more comes from it
            await("the panel notices", { robot.robot.connection.value }) { robot.robot.connection.value !is ConnectionState.Connected }
            await("the movement is shown as of when it was last heard", { onNodeWithTag("result-$id").text() }) {
                onNodeWithTag("result-$id").isStale() && ago.containsMatchIn(onNodeWithTag("result-$id").text())
            }
            assertTrue(onNodeWithTag("robot-queue").isStale(), onNodeWithTag("robot-queue").text())

            onNodeWithTag("tab-SENSORS").performClick()
            for (tag in listOf("wheels-speed", "wheels-pwm", "loco-mode", "loco-queue", "line-status", "battery", "robot-time")) {
                assertTrue(onNodeWithTag(tag).isStale(), "$tag is shown as live: ${onNodeWithTag(tag).text()}")
            }
            await("the banner says why and since when", { onNodeWithTag("stale-banner").text() }) {
                exists("stale-banner") && onNodeWithTag("stale-banner").text().let { "link" in it && ago.containsMatchIn(it) }
            }

            onNodeWithTag("tab-OVERVIEW").performClick()
            for (cell in listOf("battery", "mode", "speed", "line", "track")) {
                val node = onNodeWithTag("overview-$cell-PocketBot-1", useUnmergedTree = true)
                assertTrue(node.isStale(), "overview $cell is shown as live: ${node.text()}")
            }
            val age = onNodeWithTag("overview-age-PocketBot-1", useUnmergedTree = true).text()
            assertTrue(ago.containsMatchIn(age), age)

            // Back: live again everywhere.
            robot.emulated!!.reconnectLink()
            await("live again", { onNodeWithTag("overview-speed-PocketBot-1", useUnmergedTree = true).text() }) {
                !onNodeWithTag("overview-speed-PocketBot-1", useUnmergedTree = true).isStale()
            }
        }
    }

    @Test
    fun floatSettingsReadAsTypedAndAnEnumSettingIsChosenByName() = PanelFixture().use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            val robot = connectRobot(f)
            onNodeWithTag("tab-SETTINGS").performClick()
            onNodeWithTag("settings-list").performScrollToKey("line_pid.kp")
            assertEquals("0.0004", onNodeWithTag("setting-line_pid.kp").text(), "the robot's default, as the docs write it")
            onNodeWithTag("setting-line_pid.kp").performTextReplacement("0.00025")
            onNodeWithTag("write-line_pid.kp").performClick()
            await("acknowledged", { onNodeWithTag("status-line_pid.kp").text() }) { onNodeWithTag("status-line_pid.kp").text() == "acknowledged: 0.00025" }
            assertEquals("0.00025", onNodeWithTag("setting-line_pid.kp").text(), "the robot's float, as typed")
            assertEquals(0.00025f, f.robotFloat("line_pid.kp"))
            onNodeWithTag("settings-list").performScrollToKey("profile.accel_mps2")
            assertTrue(Regex("""^\d+(\.\d{1,4})?$""").matches(onNodeWithTag("setting-profile.accel_mps2").text()), onNodeWithTag("setting-profile.accel_mps2").text())

            onNodeWithTag("settings-list").performScrollToKey("sync.mode")
            assertEquals("none, full, reduced", onNodeWithTag("range-sync.mode").text())
            assertTrue(onNodeWithTag("setting-sync.mode-full").isSelected(), "the robot's mode, by name")
            onNodeWithTag("setting-sync.mode-reduced").performClick()
            await("the robot sends reduced state") { robot.robot.reflector.mode.value == SyncMode.REDUCED }
            await("and the panel says so") { onNodeWithTag("setting-sync.mode-reduced").isSelected() }
            // In reduced sync what full states alone carry is greyed as stale; what reduced states carry is live.
            onNodeWithTag("tab-SENSORS").performClick()
            await("the banner says so") { exists("stale-banner") && onNodeWithTag("stale-banner").text().startsWith("Reduced state") }
            assertTrue(onNodeWithTag("loco-mode").isStale(), "the locomotion mode is not live in reduced sync")
            assertTrue(onNodeWithTag("line-bars").isStale(), "the line spots are not live in reduced sync")
            assertTrue(!onNodeWithTag("line-status").isStale(), "the line position is live in reduced sync")
            assertTrue(!onNodeWithTag("wheels-speed").isStale(), "the wheel speeds are live in reduced sync")
            onNodeWithTag("tab-SETTINGS").performClick()
            onNodeWithTag("settings-list").performScrollToKey("sync.mode")
            onNodeWithTag("setting-sync.mode-full").performClick()
            await("full state again", { "${robot.edits.value} ${robot.robot.reflector.mode.value} ${robot.robot.settings.sync.mode.value} " }) {
                robot.robot.reflector.mode.value == SyncMode.FULL
            }

            onNodeWithTag("tab-TUNING").performClick()
            onNodeWithTag("controller-LINE").performClick()
            await("the gain as typed", { onNodeWithTag("gain-kp").text() }) { onNodeWithTag("gain-kp").text() == "0.00025" }
            onNodeWithTag("tab-COMMANDS").performClick()
            assertTrue(Regex("""^\d+(\.\d{1,3})?$""").matches(onNodeWithTag("track-speed").text()), onNodeWithTag("track-speed").text())
        }
    }

    @Test
    fun theStepTestAsksFirstRunsTheChosenSizeAndShowsOnlyItsOwnControllersResult() = PanelFixture(world = "straight").use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            val robot = connectRobot(f)
            val handle = robot.emulated!!
            onNodeWithTag("tab-TUNING").performClick()
            onNodeWithTag("controller-ROBOT_SPEED").performClick()
            onNodeWithTag("step-test").performClick()
            await("a question first", { exists("step-confirm") }) { exists("step-confirm") }
            assertTrue(onNodeWithTag("step-describe").text().contains("drives 0.3 m straight ahead at 0.2 m/s"), onNodeWithTag("step-describe").text())
            Thread.sleep(300)
            assertEquals(0.0, handle.trueWheelDistances.leftM, 1e-4, "nothing moves before the user says so")
            onNodeWithTag("step-distance").performTextReplacement("0.2")
            await("the question follows the size", { onNodeWithTag("step-describe").text() }) { onNodeWithTag("step-describe").text().contains("drives 0.2 m") }
            onNodeWithTag("step-confirm").performClick()
            await("the step test ran", {
                "running ${robot.tuning.running.value}, notices ${f.panel.notices.value.map { it.text }}, asking ${exists("step-confirm")}, " +
                    "active ${robot.tuning.active.value}, captures ${robot.tuning.captures.value}, wheels ${handle.trueWheelDistances}"
            }) {
                robot.tuning.captured != null && !robot.tuning.running.value
            }
            val driven = handle.trueWheelDistances.let { (it.leftM + it.rightM) / 2 }
            assertTrue(abs(driven - 0.2) < 0.02, "drove $driven m of the 0.2 m asked")
            await("its figures", { onNodeWithTag("step-figures").text() }) { onNodeWithTag("step-figures").text().contains("rise") }

            // Another loop shows its own result (none yet), not the robot speed's.
            onNodeWithTag("controller-WHEEL_SPEED").performClick()
            await("no result for the wheel speed yet", { onNodeWithTag("step-figures").text() }) { onNodeWithTag("step-figures").text().contains("run a step test") }
            onNodeWithTag("controller-ROBOT_SPEED").performClick()
            await("the robot speed's result is back", { onNodeWithTag("step-figures").text() }) { onNodeWithTag("step-figures").text().contains("rise") }

            // Leaving the tab ends the fast reduced state: the other views are live again.
            assertEquals(SyncMode.REDUCED, robot.robot.reflector.mode.value)
            onNodeWithTag("tab-COMMANDS").performClick()
            await("full state again") { robot.robot.reflector.mode.value == SyncMode.FULL }
            await("the queue is live", { onNodeWithTag("robot-queue").text() }) { !onNodeWithTag("robot-queue").isStale() }
        }
    }

    @Test
    fun aMovementOverLineFollowingAsksFirstAndARunningMovementSaysRunning() = PanelFixture().use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            val robot = connectRobot(f)
            onNodeWithTag("tab-COMMANDS").performClick()
            onNodeWithTag("follow-start").performClick()
            await("following") { robot.robot.state.value.locomotion.mode == LocoMode.LINE_FOLLOW }
            onNodeWithTag("move-amount").performTextReplacement("0.3")
            onNodeWithTag("move-speed").performTextReplacement("0.1")
            onNodeWithTag("enqueue").performClick()
            await("a question first", { exists("enqueue-confirm") }) { exists("enqueue-confirm") }
            assertTrue(onNodeWithTag("enqueue-warning").text().contains("ends line following"), onNodeWithTag("enqueue-warning").text())
            Thread.sleep(300)
            assertEquals(LocoMode.LINE_FOLLOW, robot.robot.state.value.locomotion.mode, "still following until the user says so")
            assertTrue(robot.movements.value.isEmpty())
            onNodeWithTag("enqueue-confirm").performClick()
            await("queued") { robot.movements.value.isNotEmpty() }
            val id = robot.movements.value.single().handle.id
            await("it runs and says so", { onNodeWithTag("result-$id").text() }) { onNodeWithTag("result-$id").text() == "running" }
            await("it ends", { onNodeWithTag("result-$id").text() }) { onNodeWithTag("result-$id").text().startsWith("finished") }
        }
    }

    @Test
    fun theMovementFormKeepsItsInputAndRepeatedReconnectFailuresAreOneCountedLine() = PanelFixture(world = "straight").use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            val robot = connectRobot(f)
            onNodeWithTag("tab-COMMANDS").performClick()
            onNodeWithTag("kind-ARC").performClick()
            onNodeWithTag("move-amount").performTextReplacement("45")
            onNodeWithTag("move-radius").performTextReplacement("0.25")
            onNodeWithTag("move-speed").performTextReplacement("0.12")
            onNodeWithTag("tab-CONSOLE").performClick()

            // The robot's link goes down and stays down: the SDK tries again and again.
            robot.emulated!!.disconnectLink()
            // During an attempt the state is Reconnecting, between attempts Lost with the failed attempt's number.
            await("many attempts failed", { robot.robot.connection.value }) {
                when (val c = robot.robot.connection.value) {
                    is ConnectionState.Reconnecting -> c.attempt >= 6
                    is ConnectionState.Lost -> (Regex("reconnect attempt (\\d+)").find(c.reason)?.groupValues?.get(1)?.toInt() ?: 0) >= 6
                    else -> false
                }
            }
            val failures = onAllNodes(hasTestTag("console-line") and hasText("link is down", substring = true)).fetchSemanticsNodes()
            assertEquals(1, failures.size, "one line for the repeated failure, not one per attempt")
            val line = onAllNodes(hasTestTag("console-line") and hasText("link is down", substring = true))[0].text()
            assertTrue(Regex("""\d+ times""").containsMatchIn(line), line)
            val link = onNodeWithTag("robot-link-PocketBot-1", useUnmergedTree = true).text()
            assertTrue(Regex("""down for \d+ s""").containsMatchIn(link), link)
            assertEquals(1, Regex(Regex.escape(robot.address)).findAll(link).count(), "the address once: $link")
            val driver = onNodeWithTag("driver-PocketBot-1", useUnmergedTree = true).text()
            assertTrue(driver.endsWith("drove it when last heard"), "who drives is not known while the link is down: $driver")

            robot.emulated!!.reconnectLink()
            await("back") { robot.robot.connection.value == ConnectionState.Connected }
            onNodeWithTag("tab-COMMANDS").performClick()
            assertEquals("45", onNodeWithTag("move-amount").text(), "what was typed is still there")
            assertEquals("0.25", onNodeWithTag("move-radius").text())
            assertEquals("0.12", onNodeWithTag("move-speed").text())
        }
    }
}

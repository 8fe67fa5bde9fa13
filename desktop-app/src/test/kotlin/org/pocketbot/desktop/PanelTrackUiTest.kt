package org.pocketbot.desktop

import androidx.compose.ui.test.ExperimentalTestApi
import androidx.compose.ui.test.assertIsDisplayed
import androidx.compose.ui.test.hasTestTag
import androidx.compose.ui.test.onNodeWithTag
import androidx.compose.ui.test.performClick
import androidx.compose.ui.test.performTextReplacement
import androidx.compose.ui.test.runComposeUiTest
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.protocol.TrackStatus
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/**
 * Thesis A.3 from the panel: three robots on the emulator's `track` world, their firmware running the track behaviour,
 * started, reversed and stopped for all robots at once from the Commands view, watched in the Overview.
 */
@OptIn(ExperimentalTestApi::class)
class PanelTrackUiTest {
    @Test
    fun theTrackBehaviourStartsOnAllRobotsShowsTheTokenReversesAndStops() = PanelFixture(world = "track", robots = 3).use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            await("three robots found") { (1..3).all { exists("tick-emulator:$it") } }
            onNodeWithTag("connect-all").performClick()
            await("three robots connected") { f.panel.robots.value.size == 3 }
            val handles = (1..3).map { f.emulator.handleFor("emulator:$it")!! }
            fun statuses() = handles.map { it.state().track.status }
            assertEquals(List(3) { TrackStatus.OFF }, statuses())
            val selected = f.panel.selected.value!!
            val id = selected.robot.identity.robotId
            onNodeWithTag("tab-COMMANDS").performClick()

            // The speed: out of range, the robot's reason shows and it keeps its value; in range, the robot holds it.
            val speedBefore = f.robotFloat("track.speed_mps", id)
            onNodeWithTag("track-speed").performTextReplacement("fast")
            onNodeWithTag("track-speed-set").performClick()
            assertEquals("refused: not a number: fast", onNodeWithTag("track-speed-status").text())
            onNodeWithTag("track-speed").performTextReplacement("0.5")
            onNodeWithTag("track-speed-set").performClick()
            await("the refusal", { onNodeWithTag("track-speed-status").text() }) { onNodeWithTag("track-speed-status").text().startsWith("refused: ") }
            assertEquals(speedBefore, f.robotFloat("track.speed_mps", id))
            onNodeWithTag("track-speed").performTextReplacement("0.12")
            onNodeWithTag("track-speed-set").performClick()
            await("the speed acknowledged", { onNodeWithTag("track-speed-status").text() }) {
                onNodeWithTag("track-speed-status").text().startsWith("acknowledged: ") && f.robotFloat("track.speed_mps", id) == 0.12f
            }

            onNodeWithTag("track-start-all").assertIsDisplayed().performClick()
            await("every robot runs the behaviour", ::statuses) { TrackStatus.OFF !in statuses() }
            await("the card shows it", { onNodeWithTag("track-status").text() }) { !onNodeWithTag("track-status").text().startsWith("off") }
            await("a robot holds the token") { handles.any { it.state().track.token != 0 } }

            onNodeWithTag("tab-OVERVIEW").performClick()
            val names = (1..3).map { "PocketBot-$it" }
            // An overview row is one click target: its cells are found in the unmerged tree.
            fun trackCells() = names.map { onNodeWithTag("overview-track-$it", useUnmergedTree = true).text() }
            fun lit(name: String) = onAllNodes(hasTestTag("overview-token-$name"), useUnmergedTree = true).fetchSemanticsNodes().isNotEmpty()
            await("the overview shows every robot running", ::trackCells) { trackCells().none { it.startsWith("off") } }
            await("the overview shows the token holder's orange light", { handles.map { it.state().track.token } }) {
                val holders = handles.filter { it.state().track.token != 0 }.map { "PocketBot-${it.id}" }
                holders.isNotEmpty() && holders.all(::lit) && names.filterNot { it in holders }.none(::lit)
            }

            onNodeWithTag("tab-COMMANDS").performClick()
            onNodeWithTag("track-reverse-all").assertIsDisplayed().performClick()
            val turned = mutableSetOf<Int>()
            await("every robot turns round", { turned }) {
                handles.filter { it.state().track.status == TrackStatus.TURNING }.forEach { turned += it.id }
                turned.size == 3
            }

            onNodeWithTag("track-stop-all").assertIsDisplayed().performClick()
            await("every robot stopped", ::statuses) { statuses().all { it == TrackStatus.OFF } }
            await("its motors off", { handles.map { it.pwmPermille } }) { handles.all { it.pwmPermille == (0 to 0) } }
            await("the card says so", { onNodeWithTag("track-status").text() }) { onNodeWithTag("track-status").text().startsWith("off") }
            assertTrue(f.panel.notices.value.none { it.isError }, "no errors: ${f.panel.notices.value.map { it.text }}")
        }
    }
}

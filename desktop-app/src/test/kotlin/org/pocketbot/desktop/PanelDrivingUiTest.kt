package org.pocketbot.desktop

import androidx.compose.ui.test.ComposeUiTest
import androidx.compose.ui.test.ExperimentalTestApi
import androidx.compose.ui.test.hasTestTag
import androidx.compose.ui.test.onNodeWithTag
import androidx.compose.ui.test.performClick
import androidx.compose.ui.test.runComposeUiTest
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.sdk.RobotEvent
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.Role
import org.pocketbot.sdk.connect
import java.io.File
import java.net.InetSocketAddress
import java.util.concurrent.TimeUnit
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/**
 * The panel beside other hosts on the same robot, as people meet it: `pocketbot` run beside it as a process of its
 * own, a phone that takes a robot over. The panel says who drives, watches while another host does, tells its user
 * when the robot was taken from it, and takes it back with its button.
 */
@OptIn(ExperimentalTestApi::class)
class PanelDrivingUiTest {
    /** `pocketbot` as a process of its own, as a user runs it beside the panel. */
    private class Cli(vararg args: String) {
        private val process = ProcessBuilder(
            File(System.getProperty("java.home"), "bin/java").path, "-cp", System.getProperty("java.class.path"),
            "org.pocketbot.cli.MainKt", *args,
        ).start()

        /** Waits for the end; returns the exit code, stdout and stderr. */
        fun await(): Triple<Int, String, String> {
            check(process.waitFor(GUARD_MS, TimeUnit.MILLISECONDS)) { process.destroyForcibly(); "pocketbot did not end" }
            return Triple(process.exitValue(), process.inputStream.bufferedReader().readText(), process.errorStream.bufferedReader().readText())
        }
    }

    private fun served() = PanelFixture(world = "round", robots = 1, serveAt = InetSocketAddress(ListenAddress.LOOPBACK, 0))

    @Test
    fun theCliWatchesBesideThePanelAndTakesTheRobotOnlyWhenToldWhileThePanelSaysWhoDrives() = served().use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            runBlocking { f.panel.connectEmbedded() }
            f.panel.serveEmulator()
            val robot = "tcp://127.0.0.1:${f.emulator.handleFor("emulator:1")!!.tcpPort}"
            await("the panel drives") { driver() == "this panel drives it" }

            val (code, out, err) = Cli("--json", "info", robot).await()
            assertEquals(0, code, err)
            assertTrue(out.contains("\"driver\":\"panel@"), out)
            waitForIdle()
            assertEquals("this panel drives it", driver(), "info disturbed nobody")
            assertTrue(!exists("watching-banner") && !exists("notice"), "and nobody was told anything")

            val (refusedCode, _, refusedErr) = Cli("move", robot, "straight", "0.05").await()
            assertEquals(8, refusedCode, refusedErr)
            assertTrue(Regex("PocketBot-1 is driven by panel@\\S+ \\(use --take-over\\)").containsMatchIn(refusedErr), refusedErr)

            val taking = Cli("move", robot, "straight", "0.25", "--speed", "0.1", "--take-over", "--wait")
            await("the panel watches while the CLI drives", { driver() }) {
                exists("watching-banner") && driver()?.startsWith("watching: cli@") == true
            }
            await("the panel's user is told") {
                onAllNodes(hasTestTag("notice")).fetchSemanticsNodes().isNotEmpty() &&
                    onNodeWithTag("notice").text().startsWith("PocketBot-1 was taken over by cli@")
            }
            val (movedCode, movedOut, movedErr) = taking.await()
            assertEquals(0, movedCode, movedErr)
            assertTrue(movedOut.contains("finished"), movedOut)
            await("the CLI said goodbye: the panel drives again", { driver() }) {
                !exists("watching-banner") && driver() == "this panel drives it"
            }
        }
    }

    @Test
    fun aPhoneTakesTheRobotOverAndThePanelTakesItBackWithItsButton() = served().use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            runBlocking { f.panel.connectEmbedded() }
            val phone = runBlocking {
                f.emulator.handleFor("emulator:1")!!.device().connect(f.scope, RobotOptions { role = Role.TAKE_OVER; hostLabel = "phone@pixel" })
            }
            val phoneHeard = java.util.concurrent.LinkedBlockingQueue<RobotEvent>()
            val listening = f.scope.launchCollect(phone, phoneHeard)
            await("the panel shows the phone drives") {
                exists("watching-banner") && driver() == "watching: phone@pixel drives it"
            }
            onNodeWithTag("banner-take-over").performClick()
            await("the panel drives again") { !exists("watching-banner") && driver() == "this panel drives it" }
            val told = phoneHeard.poll(GUARD_MS, TimeUnit.MILLISECONDS) as RobotEvent.DriverChanged
            assertTrue(told.taken && told.driving.driver!!.startsWith("panel@"), "the phone was told: $told")
            listening.cancel()
            runBlocking { phone.disconnect() }
        }
    }
}

/** What PocketBot-1's card in the sidebar says of who drives it (a text inside the card's merged semantics), or null. */
@OptIn(ExperimentalTestApi::class)
private fun ComposeUiTest.driver(): String? =
    if (onAllNodes(hasTestTag("driver-PocketBot-1"), useUnmergedTree = true).fetchSemanticsNodes().isEmpty()) null
    else onNodeWithTag("driver-PocketBot-1", useUnmergedTree = true).text()

/** Collects [robot]'s events into [into] until cancelled. */
private fun kotlinx.coroutines.CoroutineScope.launchCollect(robot: org.pocketbot.sdk.Robot, into: java.util.concurrent.BlockingQueue<RobotEvent>) =
    launch { robot.events.collect { into.put(it) } }

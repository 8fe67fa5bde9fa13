package org.pocketbot.desktop

import androidx.compose.ui.test.ExperimentalTestApi
import androidx.compose.ui.test.onAllNodesWithText
import androidx.compose.ui.test.onNodeWithTag
import androidx.compose.ui.test.performClick
import androidx.compose.ui.test.performTextReplacement
import androidx.compose.ui.test.runComposeUiTest
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.sdk.mqtt.connectBroker
import org.pocketbot.sdk.mqtt.startGateway
import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import kotlin.math.abs
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

/**
 * The panel with `--broker`: a robot of another host (an emulator behind a gateway, the real firmware) found through
 * a real Mosquitto run with the shipped configuration, shown with its gateway, connected, driven and read like a
 * robot of this host. Ground truth from the emulator.
 */
@OptIn(ExperimentalTestApi::class)
class PanelBrokerUiTest {
    @Test
    fun aRobotFoundThroughABrokerShowsItsGatewayAndIsDrivenAndReadLive() = MosquittoBroker.start().use { broker ->
        val elsewhere = CoroutineScope(SupervisorJob() + Dispatchers.Default)
        val remote = Emulator.local(robots = 1, world = "round")
        try {
            remote.start(Speed.Realtime(1.0))
            val gateway = runBlocking { elsewhere.startGateway("lab1", broker.options("lab1"), remote.discoverer()) }
            runBlocking { withTimeout(GUARD_MS.milliseconds) { gateway.robots.first { it.isNotEmpty() } } }
            val client = runBlocking { elsewhere.connectBroker(broker.options("alice")) }
            PanelFixture(sources = mapOf("broker ${broker.url}" to client.discoverer())).use { f ->
                runComposeUiTest {
                    setContent { PanelApp(f.panel) }
                    await("the broker's robot in the sidebar", { f.panel.found.value.map { it.name } }) {
                        f.panel.found.value.any { it.gateway == "lab1" }
                    }
                    val found = f.panel.found.value.single { it.gateway == "lab1" }
                    assertEquals("lab1/PocketBot-1", found.name)
                    assertEquals(1, onAllNodesWithText("lab1/PocketBot-1").fetchSemanticsNodes().size, "listed with its gateway")
                    onNodeWithTag("tick-${found.address}").performClick()
                    onNodeWithTag("connect-ticked").performClick()
                    await("connected", { f.panel.connectFailures.value }) { exists("robot-lab1/PocketBot-1") }
                    onNodeWithTag("robot-lab1/PocketBot-1").performClick()
                    val robot = f.panel.selected.value!!
                    assertEquals("lab1/PocketBot-1", robot.name)
                    assertEquals("lab1", robot.gateway)
                    val link = onNodeWithTag("robot-link-lab1/PocketBot-1", useUnmergedTree = true).text()
                    assertTrue(link.startsWith("connected") && "/lab1/" in link, "the sidebar's link line: $link")

                    // Driven from the Commands view; its live state shows the movement while it runs, then its result.
                    onNodeWithTag("tab-COMMANDS").performClick()
                    val sim = remote.robot(1)
                    val heading = sim.truePose.headingRad
                    onNodeWithTag("kind-ROTATE").performClick()
                    onNodeWithTag("move-amount").performTextReplacement("90")
                    onNodeWithTag("move-speed").performTextReplacement("0.1")
                    onNodeWithTag("enqueue").performClick()
                    await("the robot's state says it moves", { onNodeWithTag("robot-queue").text() }) {
                        onNodeWithTag("robot-queue").text().startsWith("robot: movement, 1 running")
                    }
                    await("the movement finished", { robot.movements.value.map { it.result } }) {
                        robot.movements.value.singleOrNull()?.result != null
                    }
                    val id = robot.movements.value.single().handle.id
                    assertTrue(onNodeWithTag("result-$id").text().startsWith("finished"), onNodeWithTag("result-$id").text())
                    val turned = Math.toDegrees(Math.IEEEremainder(sim.truePose.headingRad - heading, 2 * Math.PI))
                    assertTrue(abs(turned - 90) < 10, "the robot of the other host turned $turned degrees for 90")
                    await("its state idle again", { onNodeWithTag("robot-queue").text() }) {
                        onNodeWithTag("robot-queue").text().startsWith("robot: idle")
                    }
                    assertTrue(gateway.stats.value.sessions >= 1 && gateway.stats.value.dropped == 0L, "${gateway.stats.value}")
                }
            }
            runBlocking { client.close(); gateway.close() }
        } finally {
            elsewhere.cancel()
            remote.close()
        }
    }
}

package org.pocketbot.desktop

import androidx.compose.ui.test.ExperimentalTestApi
import androidx.compose.ui.test.onNodeWithTag
import androidx.compose.ui.test.performClick
import androidx.compose.ui.test.runComposeUiTest
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.runBlocking
import org.junit.jupiter.api.Assumptions.assumeTrue
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.Pose
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.transport.EmulatorDiscoverer
import org.pocketbot.sdk.transport.TransportLostException
import org.pocketbot.sdk.NotDriverException
import org.pocketbot.sdk.Role
import java.net.Inet4Address
import java.net.NetworkInterface
import kotlin.math.hypot
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue

/**
 * The panel's embedded emulator served on the network, as someone without a robot uses it: the panel draws the world,
 * a phone (here the SDK, as the Android app uses it, from this machine's network address) takes a robot of it over
 * while the panel watches it.
 */
@OptIn(ExperimentalTestApi::class)
class PanelNetworkUiTest {
    @Test
    fun aPhoneOnTheNetworkTakesOverARobotThePanelDrawsAndWatchesAndThePanelDrivesItAgainAfterwards() = PanelFixture(world = "round", robots = 2).use { f ->
        val found = NetworkInterface.getNetworkInterfaces().toList().filter { it.isUp && !it.isLoopback }
            .flatMap { it.inetAddresses.toList() }.firstOrNull { it is Inet4Address && !it.isLinkLocalAddress }?.hostAddress
        assumeTrue(found != null, "this machine has no network address besides loopback: no phone could reach the panel here")
        val network: String = found!!
        val phone = CoroutineScope(SupervisorJob() + Dispatchers.Default)
        try {
            runComposeUiTest {
                setContent { PanelApp(f.panel) }
                val ours = runBlocking { f.panel.connectEmbedded() }
                val panelsOne = ours.single { it.name == "PocketBot-1" }
                onNodeWithTag("tab-WORLD").performClick()
                onNodeWithTag("emu-serve").performClick()
                await("the address to type into the phone", { f.emulator.serving.value }) { exists("emu-serving") }
                val served = f.emulator.serving.value!!
                assertTrue("$network:${served.controlPort}" in served.addresses, "offered ${served.addresses}")
                assertTrue(onNodeWithTag("emu-serving").text().contains("$network:${served.controlPort}"), onNodeWithTag("emu-serving").text())

                // The phone finds the robots at the computer's network address and takes robot 1 over.
                val devices = runBlocking { EmulatorDiscoverer(network, served.controlPort).list() }
                assertEquals(listOf("PocketBot-1", "PocketBot-2"), devices.map { it.name })
                val driven = runBlocking {
                    devices[0].connect(phone, RobotOptions { settingsCache = InMemorySettingsCache(); role = Role.TAKE_OVER; hostLabel = "phone@wifi" })
                }
                val sim = panelsOne.emulated!!
                await("the panel shows who drives robot 1", { panelsOne.driving.value }) {
                    exists("emu-driven") && onNodeWithTag("emu-driven").text() == "PocketBot-1 driven by phone@wifi"
                }
                assertEquals(ConnectionState.Connected, panelsOne.robot.connection.value, "the panel stays connected to robot 1, and watches it")
                assertTrue(ours.single { it.name == "PocketBot-2" }.driving.value.byThisHost, "and drives robot 2")

                sim.place(Pose.ofDegrees(0.4, 0.4, 0.0)) // the open floor inside the track
                val start = sim.truePose
                val result = runBlocking { driven.locomotion.enqueue(Movement.Straight(0.08, speedMps = 0.1)).await() }
                assertEquals(MovementOutcome.FINISHED, result.outcome, "$result")
                val moved = hypot(sim.truePose.xM - start.xM, sim.truePose.yM - start.yM)
                assertTrue(moved in 0.075..0.085, "the phone drove robot 1 ${moved * 1000} mm of 80")
                assertEquals(0L, driven.linkStats.value.reconnects, "the panel never took the robot back while the phone drove it")
                assertEquals(0L, panelsOne.robot.linkStats.value.reconnects, "nor was its own link cut")
                val drawn = f.emulator.world.value.robots.single { it.id == 1 }.pose
                assertTrue(hypot(drawn.xM - sim.truePose.xM, drawn.yM - sim.truePose.yM) < 0.01, "the world view draws where the phone drove it: $drawn")
                // A command of the panel meanwhile is refused, naming the driver.
                val refused = assertFailsWith<NotDriverException> { runBlocking { panelsOne.robot.locomotion.enqueue(Movement.Straight(0.01, 0.1)) } }
                assertEquals("PocketBot-1 is driven by phone@wifi", refused.message)

                // The phone lets go: the panel, which asked to drive, drives its robot again.
                runBlocking { driven.disconnect() }
                await("the panel drives robot 1 again", { panelsOne.driving.value }) {
                    panelsOne.driving.value.byThisHost && !exists("emu-driven")
                }

                onNodeWithTag("emu-serve-stop").performClick()
                await("off the network") { exists("emu-serve") && f.emulator.serving.value == null }
                assertFailsWith<TransportLostException> { runBlocking { EmulatorDiscoverer(network, served.controlPort).list() } }
            }
        } finally {
            phone.cancel()
        }
    }
}

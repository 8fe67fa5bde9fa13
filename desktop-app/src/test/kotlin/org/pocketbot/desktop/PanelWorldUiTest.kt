package org.pocketbot.desktop

import androidx.compose.ui.geometry.Size
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.graphics.PixelMap
import androidx.compose.ui.graphics.toPixelMap
import androidx.compose.ui.test.ExperimentalTestApi
import androidx.compose.ui.test.captureToImage
import androidx.compose.ui.test.onNodeWithTag
import androidx.compose.ui.test.onRoot
import androidx.compose.ui.test.performClick
import androidx.compose.ui.test.performTextReplacement
import androidx.compose.ui.test.runComposeUiTest
import androidx.compose.ui.test.runDesktopComposeUiTest
import kotlinx.coroutines.runBlocking
import org.pocketbot.desktop.model.WorldSnapshot
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.desktop.ui.RobotShape
import org.pocketbot.desktop.ui.WorldFrame
import org.pocketbot.desktop.ui.floorColour
import org.pocketbot.desktop.ui.frontMarkColour
import org.pocketbot.desktop.ui.tokenColour
import org.pocketbot.emulator.world.Worlds
import org.pocketbot.protocol.LedFlags
import org.pocketbot.sdk.Pose
import kotlin.math.abs
import kotlin.test.Test
import kotlin.test.assertTrue

/**
 * The World view as drawn, read back in pixels: which way each robot faces, who holds the track token, and every
 * shipped world on offer.
 */
@OptIn(ExperimentalTestApi::class)
class PanelWorldUiTest {
    @Test
    fun everyShippedWorldIsOfferedInFullEvenInASmallWindow() = PanelFixture().use { f ->
        runComposeUiTest { // 1024 x 768: narrower than the panel's own window
            setContent { PanelApp(f.panel) }
            onNodeWithTag("tab-WORLD").performClick()
            val width = onRoot().fetchSemanticsNode().size.width
            for (name in Worlds.names) {
                val bounds = onNodeWithTag("world-$name").fetchSemanticsNode().boundsInRoot
                assertTrue(bounds.width > 20 && bounds.left >= 0 && bounds.right <= width, "world $name is not fully shown: $bounds in $width px")
            }
        }
    }

    @Test
    fun eachRobotIsDrawnFacingItsHeadingWithAWhiteMarkOnItsFront() = PanelFixture(world = "round").use { f ->
        runDesktopComposeUiTest(1440, 900) {
            setContent { PanelApp(f.panel) }
            onNodeWithTag("tab-WORLD").performClick()
            f.emulator.pause()
            val robot = f.emulator.handleFor("emulator:1")!!
            // Headings that a mirrored or unrotated drawing would get wrong: the mark would land elsewhere.
            for (degrees in listOf(60.0, 200.0, -100.0)) {
                val pose = Pose.ofDegrees(0.4, 0.4, degrees)
                robot.place(pose)
                await("the world view shows the robot at $degrees°", { f.emulator.world.value.robots.single().pose }) {
                    f.emulator.world.value.robots.single().pose.let { abs(it.headingRad - pose.headingRad) < 1e-6 && abs(it.xM - 0.4) < 1e-6 }
                }
                waitForIdle()
                val (pixels, frame) = world(f.emulator.world.value)
                val front = pixels.at(frame, pose, RobotShape.insideFrontMark)
                val rear = pixels.at(frame, pose, RobotShape.insideRear)
                assertTrue(front.near(frontMarkColour), "at $degrees°, the robot's front is not marked: $front")
                assertTrue(!rear.near(frontMarkColour) && !rear.near(floorColour), "at $degrees°, its rear is not its body: $rear")
            }
        }
    }

    @Test
    fun theTrackTokenHolderShowsItsOrangeLightAndNoOtherRobotDoes() = PanelFixture(world = "track", robots = 3).use { f ->
        runDesktopComposeUiTest(1440, 900) {
            setContent { PanelApp(f.panel) }
            val robots = runBlocking { f.panel.connectEmbedded() }
            f.panel.everyRobot { it.startTrack() }
            val handles = (1..3).map { f.emulator.handleFor("emulator:$it")!! }
            await("a robot holds the token", { handles.map { it.led } }) { handles.any { it.led and LedFlags.TOKEN != 0 } }
            onNodeWithTag("tab-WORLD").performClick()
            f.emulator.pause()
            // Paused in a hand-over, the token is on its way and no robot holds it: a few steps more and one does.
            var steps = 0
            do f.emulator.singleStep() while (f.emulator.world.value.robots.none { it.holdsToken } && ++steps < 2000)
            val paused = f.emulator.world.value.timeMs
            // A snapshot the sampler took just before the last step may still replace it once: wait for this moment's.
            await("the world view shows the paused world with a token holder") {
                f.emulator.world.value.let { w -> w.timeMs >= paused && w.robots.any { it.holdsToken } }
            }
            waitForIdle()
            val snapshot = f.emulator.world.value
            val (pixels, frame) = world(snapshot)
            for (t in snapshot.robots) {
                val centre = pixels.at(frame, t.pose, 0.0 to 0.0)
                if (t.holdsToken) assertTrue(centre.near(tokenColour), "robot ${t.id} holds the token, but its light is $centre")
                else assertTrue(!centre.near(tokenColour), "robot ${t.id} does not hold the token, but shows an orange light")
            }
            val holder = robots.single { r -> snapshot.robots.single { it.address == r.address }.holdsToken }
            val description = onNodeWithTag("world-canvas").description()
            assertTrue(description.endsWith("the track token is with ${holder.name}"), description)
        }
    }

    @Test
    fun odometryOutlinesStartOnTheirRobotsAfterAReconnectAndAWorldRestart() = PanelFixture(world = "round").use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            fun offsets() = f.panel.robots.value.map { r -> r.name to r.robot.odometry.pose.value.distanceTo(r.emulated!!.truePose) }
            fun onTheirRobots() = f.panel.robots.value.isNotEmpty() && offsets().all { it.second < 0.005 }
            connectRobot(f)
            await("the outline on its robot", ::offsets, ::onTheirRobots)

            onNodeWithTag("disconnect-PocketBot-1").performClick()
            await("disconnected") { f.panel.robots.value.isEmpty() }
            connectRobot(f)
            await("the outline on its robot after a reconnect", ::offsets, ::onTheirRobots)

            onNodeWithTag("tab-WORLD").performClick()
            onNodeWithTag("world-straight").performClick()
            onNodeWithTag("emu-robots").performTextReplacement("2")
            onNodeWithTag("emu-restart").performClick()
            await("two robots on the new world", { f.panel.robots.value.map { it.name } }) {
                f.emulator.world.value.world.name == "straight" && f.panel.robots.value.size == 2
            }
            await("every outline on its robot after the world restart", ::offsets, ::onTheirRobots)
        }
    }

    /** The world canvas as pixels, and where the world's metres are on it. */
    private fun androidx.compose.ui.test.ComposeUiTest.world(snapshot: WorldSnapshot): Pair<PixelMap, WorldFrame> {
        val image = onNodeWithTag("world-canvas").captureToImage()
        val frame = WorldFrame(0.0, 0.0, snapshot.world.widthM, snapshot.world.heightM, Size(image.width.toFloat(), image.height.toFloat()))
        return image.toPixelMap() to frame
    }

    /** The colour drawn at the body point (forward, left) of a robot at [pose]. */
    private fun PixelMap.at(frame: WorldFrame, pose: Pose, point: Pair<Double, Double>): Color {
        val (x, y) = RobotShape.at(pose, point.first, point.second)
        val p = frame.at(x, y)
        return this[p.x.toInt(), p.y.toInt()]
    }

    private fun Color.near(other: Color): Boolean =
        abs(red - other.red) < 0.12f && abs(green - other.green) < 0.12f && abs(blue - other.blue) < 0.12f
}

package org.pocketbot.desktop

import androidx.compose.ui.geometry.Offset
import androidx.compose.ui.test.ExperimentalTestApi
import androidx.compose.ui.test.onAllNodesWithText
import androidx.compose.ui.test.onNodeWithTag
import androidx.compose.ui.test.performClick
import androidx.compose.ui.test.performMouseInput
import androidx.compose.ui.test.performScrollTo
import androidx.compose.ui.test.performScrollToKey
import androidx.compose.ui.test.performTextReplacement
import androidx.compose.ui.test.runComposeUiTest
import kotlinx.coroutines.flow.flowOf
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.emulator.ForeignPeer
import org.pocketbot.protocol.Colour
import org.pocketbot.protocol.LocoMode
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.toDecimalString
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.TcpRobotDevice
import kotlin.math.abs
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/**
 * More of the panel as people use it, against the embedded emulator running the real firmware: a fleet, the
 * emulator's controls, every kind of command, settings kept in EEPROM, the console, a robot with other firmware.
 */
@OptIn(ExperimentalTestApi::class)
class PanelFleetUiTest {
    private val guard = GUARD_MS

    @Test
    fun aFleetConnectsAtOnceAndDisconnectsOneByOneAndAllTogether() = PanelFixture(robots = 3).use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            waitUntil(timeoutMillis = guard) { (1..3).all { exists("tick-emulator:$it") } }
            onNodeWithTag("connect-all").performClick()
            waitUntil(timeoutMillis = guard) { f.panel.robots.value.size == 3 }
            val tags = (1..3).flatMap { listOf("overview-PocketBot-$it", "robot-PocketBot-$it") }
            await("every robot in the overview and the sidebar", { tags.filter { exists(it) } }) { tags.all { exists(it) } }
            val robots = f.panel.robots.value
            // Whatever order they connected in, every view lists them by name.
            val names = (1..3).map { "PocketBot-$it" }
            assertEquals(names, robots.map { it.name })
            for (prefix in listOf("overview-", "robot-")) {
                val tops = names.map { onNodeWithTag(prefix + it).fetchSemanticsNode().positionInRoot.y }
                assertEquals(tops.sorted(), tops, "$prefix rows top to bottom by name")
            }
            // This window is narrower than the overview's table: it scrolls sideways, and each row stays one line.
            val height = onNodeWithTag("overview-PocketBot-1").fetchSemanticsNode().size.height
            assertTrue(height < 60, "an overview row $height px high")

            onNodeWithTag("disconnect-PocketBot-2").performClick()
            waitUntil(timeoutMillis = guard) { !exists("robot-PocketBot-2") && exists("tick-emulator:2") }
            assertEquals(setOf("PocketBot-1", "PocketBot-3"), f.panel.robots.value.map { it.name }.toSet())
            waitUntil(timeoutMillis = guard) { robots.single { it.name == "PocketBot-2" }.robot.connection.value is ConnectionState.Closed }

            onNodeWithTag("disconnect-all").performClick()
            waitUntil(timeoutMillis = guard) { f.panel.robots.value.isEmpty() && !exists("overview-PocketBot-1") }
            waitUntil(timeoutMillis = guard) { robots.all { it.robot.connection.value is ConnectionState.Closed } }
            assertEquals(null, f.panel.selected.value)
        }
    }

    @Test
    fun theEmbeddedEmulatorPausesStepsOneMillisecondAndRunsFaster() = PanelFixture().use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            onNodeWithTag("tab-WORLD").performClick()
            onNodeWithTag("emu-pause").performClick()
            waitUntil(timeoutMillis = guard) { exists("emu-resume") && f.emulator.paused.value }
            Thread.sleep(200) // the world view's sampler takes the paused time
            val paused = f.emulator.world.value.timeMs
            Thread.sleep(300) // real time passes ...
            assertEquals(paused, f.emulator.world.value.timeMs, "... and simulated time stands still while paused")
            onNodeWithTag("emu-step").performClick()
            waitUntil(timeoutMillis = guard) { f.emulator.world.value.timeMs == paused + 1 }
            waitUntil(timeoutMillis = guard) { onNodeWithTag("world-title").text().contains("t = %.1f s".format((paused + 1) / 1000.0)) }

            onNodeWithTag("emu-speed-2.0").performClick()
            assertEquals(2.0, f.emulator.speed.value)
            onNodeWithTag("emu-resume").performClick()
            waitUntil(timeoutMillis = guard) { f.emulator.world.value.timeMs > paused + 500 }
            assertTrue(!f.emulator.paused.value)
        }
    }

    @Test
    fun rotateArcImmediateStopAndTheJoystickMoveTheRobot() = PanelFixture(world = "straight").use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            val robot = connectRobot(f)
            val handle = robot.emulated!!
            onNodeWithTag("tab-COMMANDS").performClick()

            fun lastResult(): String {
                val id = robot.movements.value.last().handle.id
                return onNodeWithTag("result-$id").text()
            }
            val heading = handle.truePose.headingRad
            onNodeWithTag("kind-ROTATE").performClick()
            onNodeWithTag("move-amount").performTextReplacement("90")
            onNodeWithTag("move-speed").performTextReplacement("0.1")
            onNodeWithTag("enqueue").performClick()
            waitUntil(timeoutMillis = guard) { robot.movements.value.size == 1 && lastResult().startsWith("finished") }
            val turned = Math.toDegrees(Math.IEEEremainder(handle.truePose.headingRad - heading, 2 * Math.PI))
            assertTrue(abs(turned - 90) < 10, "turned $turned degrees for 90")

            onNodeWithTag("kind-ARC").performClick()
            onNodeWithTag("move-radius").performTextReplacement("0.1")
            onNodeWithTag("move-amount").performTextReplacement("45")
            onNodeWithTag("enqueue").performClick()
            waitUntil(timeoutMillis = guard) { robot.movements.value.size == 2 && lastResult().startsWith("finished") }
            val arc = robot.movements.value.last().result!!
            assertTrue(abs(arc.done!! - 45) < 3, "the arc turned ${arc.done} of 45 degrees")

            // A long straight, stopped with the motors off at once.
            onNodeWithTag("kind-STRAIGHT").performClick()
            onNodeWithTag("move-amount").performTextReplacement("1.0")
            onNodeWithTag("move-speed").performTextReplacement("0.2")
            onNodeWithTag("enqueue").performClick()
            waitUntil(timeoutMillis = guard) { robot.movements.value.size == 3 && handle.state().wheels.speedLeftMmps > 100 }
            onNodeWithTag("stop-now").performClick()
            await("the movement stopped", { "${lastResult()}; robot ${handle.state().locomotion}, ${handle.state().wheels}" }) { lastResult().startsWith("stopped") }
            assertTrue(robot.movements.value.last().result!!.done!! < 1.0, "cut short")
            assertEquals(0 to 0, handle.pwmPermille, "motors off")

            // The joystick: held up, the robot drives forward; let go, it stops.
            val start = handle.truePose
            onNodeWithTag("joystick").performScrollTo()
            onNodeWithTag("joystick").performMouseInput {
                moveTo(center)
                press()
                repeat(4) { advanceEventTime(16); moveBy(Offset(0f, -height * 0.1f)) }
            }
            waitUntil(timeoutMillis = guard) { handle.state().wheels.let { it.speedLeftMmps > 50 && it.speedRightMmps > 50 } }
            onNodeWithTag("joystick").performMouseInput { release() }
            waitUntil(timeoutMillis = guard) { handle.state().wheels.let { it.speedLeftMmps == 0 && it.speedRightMmps == 0 } }
            assertTrue(handle.truePose.distanceTo(start) > 0.005, "the joystick moved the robot")
        }
    }

    @Test
    fun lineFollowingInColourModeSlowsDownOnRedAndStopsOnRequest() = PanelFixture(world = "colours").use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            val handle = connectRobot(f).emulated!!
            onNodeWithTag("tab-COMMANDS").performClick()
            onNodeWithTag("follow-speed").performTextReplacement("0.15")
            onNodeWithTag("follow-colours").performClick()
            onNodeWithTag("follow-start").performClick()
            waitUntil(timeoutMillis = guard) { handle.state().lineFollow.segment == Colour.RED }
            val onRed = handle.state().time.timeMs
            waitUntil(timeoutMillis = guard) { handle.state().time.timeMs > onRed + 500 }
            val speed = handle.state().wheels.let { (it.speedLeftMmps + it.speedRightMmps) / 2 }
            assertTrue(speed in 40..100, "on red at $speed mm/s: colour mode slows down to line_follow.red_speed_mps (0.07)")
            waitUntil(timeoutMillis = guard) { onNodeWithTag("follow-status").text().contains("segment red") }
            onNodeWithTag("follow-stop").performClick()
            waitUntil(timeoutMillis = guard) { handle.state().locomotion.mode != LocoMode.LINE_FOLLOW }
        }
    }

    @Test
    fun settingsAreSavedToEepromAndTheDefaultsLoaded() = PanelFixture().use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            connectRobot(f)
            val default = f.robotFloat("line_pid.kd")
            onNodeWithTag("tab-SETTINGS").performClick()
            onNodeWithTag("settings-list").performScrollToKey("line_pid.kd")
            onNodeWithTag("setting-line_pid.kd").performTextReplacement("0.125")
            onNodeWithTag("write-line_pid.kd").performClick()
            waitUntil(timeoutMillis = guard) { onNodeWithTag("status-line_pid.kd").text().startsWith("acknowledged") }
            onNodeWithTag("settings-save").performClick()
            waitUntil(timeoutMillis = guard) { f.panel.notices.value.any { "settings saved to EEPROM" in it.text } }

            onNodeWithTag("setting-line_pid.kd").performTextReplacement("0.25")
            onNodeWithTag("write-line_pid.kd").performClick()
            waitUntil(timeoutMillis = guard) { onNodeWithTag("status-line_pid.kd").text() == "acknowledged: 0.25" }
            f.panel.selected.value!!.emulated!!.reset() // a power cycle: the firmware starts from its EEPROM
            waitUntil(timeoutMillis = guard) { f.robotFloat("line_pid.kd") == 0.125f }

            onNodeWithTag("settings-defaults").performClick()
            waitUntil(timeoutMillis = guard) { f.robotFloat("line_pid.kd") == default }
            // The field shows what the robot holds now.
            waitUntil(timeoutMillis = guard) { onNodeWithTag("setting-line_pid.kd").text() == default.toDecimalString() }
        }
    }

    @Test
    fun theConsoleSetsTheRobotsLevelShowsItsTextAndFiltersByLevel() = PanelFixture(world = "straight").use { f ->
        runComposeUiTest {
            setContent { PanelApp(f.panel) }
            val robot = connectRobot(f)
            onNodeWithTag("tab-CONSOLE").performClick()
            onNodeWithTag("set-level-3").performClick()
            waitUntil(timeoutMillis = guard) { f.robotDebugLevel() == 3 && onNodeWithTag("robot-debug-level").text().endsWith("3") }
            robot.enqueue(org.pocketbot.sdk.Movement.Straight(0.02, 0.1))
            waitUntil(timeoutMillis = guard) { robot.movements.value.singleOrNull()?.result != null }
            val id = robot.movements.value.single().handle.id
            // The firmware reports a movement's start and end at level 2 and 3: shown up to trace, hidden up to errors.
            fun shown() = onAllNodesWithText("done $id", substring = true).fetchSemanticsNodes().isNotEmpty()
            waitUntil(timeoutMillis = guard) { shown() }
            onNodeWithTag("show-level-1").performClick()
            waitUntil(timeoutMillis = guard) { !shown() }
            onNodeWithTag("show-level-4").performClick()
            waitUntil(timeoutMillis = guard) { shown() }
        }
    }

    @Test
    fun aRobotWithOtherFirmwareSaysSoBesideItInTheList() = ForeignPeer(protocolVersion = ProtocolInfo.VERSION + 1).use { peer ->
        val oldFirmware = object : Discoverer {
            override fun discover() = flowOf(TcpRobotDevice("127.0.0.1", peer.port, name = ForeignPeer.NAME))
        }
        PanelFixture(sources = mapOf("old firmware" to oldFirmware)).use { f ->
            runComposeUiTest {
                setContent { PanelApp(f.panel) }
                waitUntil(timeoutMillis = guard) { exists("tick-${peer.address}") }
                onNodeWithTag("tick-${peer.address}").performClick()
                onNodeWithTag("connect-ticked").performClick()
                waitUntil(timeoutMillis = guard) { exists("connect-failure-${peer.address}") }
                val why = onNodeWithTag("connect-failure-${peer.address}").text()
                assertTrue(why.startsWith("firmware mismatch: protocol mismatch: robot speaks protocol v${ProtocolInfo.VERSION + 1}"), why)
                assertTrue("Update the robot's firmware" in why, why)
                assertTrue(f.panel.robots.value.isEmpty(), "nothing half connected")
                // The panel keeps working: the emulated robot still connects.
                connectRobot(f)
            }
        }
    }
}

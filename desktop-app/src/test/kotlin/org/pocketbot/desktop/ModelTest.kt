package org.pocketbot.desktop

import kotlinx.coroutines.delay
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.desktop.model.EditStatus
import org.pocketbot.desktop.model.SampleRing
import org.pocketbot.desktop.model.compareNatural
import org.pocketbot.desktop.ui.ColumnSpans
import org.pocketbot.desktop.ui.decimals
import org.pocketbot.desktop.ui.describe
import org.pocketbot.desktop.ui.ticks
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.Pose
import org.pocketbot.sdk.TuningSample
import java.io.File
import kotlin.test.Test
import kotlin.math.abs
import kotlin.test.assertEquals
import kotlin.test.assertIs
import kotlin.test.assertTrue

/** The panel's state holders on their own, without drawing; the robot ones against the emulator's real firmware. */
class ModelTest {
    private val guard = 30_000L

    private suspend fun until(what: String, condition: () -> Boolean) =
        withTimeout(guard) { while (!condition()) delay(20) }.also { check(condition()) { what } }

    @Test
    fun theSampleRingKeepsTheNewestInOrderAndCountsEvery() {
        val ring = SampleRing(4)
        for (t in 1L..10L) ring.add(TuningSample(t, 0.0, t.toDouble()))
        assertEquals(listOf(7L, 8L, 9L, 10L), ring.snapshot().map { it.timeMs })
        assertEquals(10, ring.added.get())
        val window = ring.window(spanMs = 2)
        assertEquals(listOf(-0.002, -0.001, 0.0), window.seconds.toList())
        assertEquals(listOf(8.0, 9.0, 10.0), window.measured.toList())
        ring.clear()
        assertEquals(emptyList(), ring.snapshot())
        assertEquals(0, ring.window(1000).seconds.size)
    }

    @Test
    fun chartTicksAreRoundAndCoverTheRange() {
        assertEquals(listOf(0.0, 0.05, 0.1, 0.15, 0.2), ticks(0.0, 0.2).map { Math.round(it * 100) / 100.0 })
        assertEquals(listOf(-1000.0, -500.0, 0.0, 500.0, 1000.0), ticks(-1000.0, 1000.0))
        assertEquals(emptyList(), ticks(1.0, 1.0))
    }

    @Test
    fun chartColumnsCoverEverySampleAndTheLineBetweenThemButNothingElse() {
        val spans = ColumnSpans(10)
        // Four samples per column, a spike among them, then a gap of three columns bridged by one segment.
        val x = floatArrayOf(0.1f, 0.3f, 0.5f, 0.7f, 1.1f, 1.3f, 1.5f, 1.7f, 5.5f)
        val y = floatArrayOf(50f, 51f, 50f, 50f, 50f, 90f, 50f, 50f, 10f)
        spans.trace(x, y)
        for (i in x.indices) {
            val c = x[i].toInt()
            assertTrue(y[i] in spans.lo[c]..spans.hi[c], "sample $i (y ${y[i]}) outside column $c: ${spans.lo[c]}..${spans.hi[c]}")
        }
        assertEquals(50f, spans.lo[0]); assertEquals(51f, spans.hi[0])
        assertEquals(90f, spans.hi[1], "the one-sample spike is kept")
        // From (1.7, 50) to (5.5, 10): 40 px down over 3.8 columns, each column gets its own part of the segment.
        for (c in 2..4) {
            val top = 50f - 40f / 3.8f * (c + 1 - 1.7f)
            val bottom = 50f - 40f / 3.8f * (c - 1.7f)
            assertEquals(top, spans.lo[c], 1e-3f, "column $c")
            assertEquals(bottom, spans.hi[c], 1e-3f, "column $c")
        }
        assertTrue((6..9).all { spans.lo[it] > spans.hi[it] }, "nothing drawn past the last sample")
        // Drawn as two 1 px lines per covered column, 1 px beyond the span; a dashed series leaves every other run out.
        assertEquals(6 * 2 * 4, spans.lines(0f).size)
        assertEquals(listOf(0.5f, 49f, 0.5f, 52f, 1.5f, 49f, 1.5f, 52f), spans.lines(0f).take(8))
        assertEquals(listOf(0f, 1f, 4f, 5f), spans.lines(0f, dash = 2).toList().chunked(8).map { it[0] - 0.5f })
        // A non-finite sample breaks the line: the columns between its neighbours stay empty.
        spans.trace(floatArrayOf(0.5f, 4.5f, 8.5f), floatArrayOf(10f, Float.NaN, 20f))
        assertTrue((1..7).all { spans.lo[it] > spans.hi[it] })
    }

    @Test
    fun numbersForPeopleHaveTheirDecimalsAsStringFormatWritesThem() {
        for (v in listOf(0.0, 4.08, 4.075, -2.345, -1.5, 0.15, 12.3456, 999.999, 1e6 + 0.125)) {
            for (places in 0..3) assertEquals("%.${places}f".format(java.util.Locale.ROOT, v), decimals(v, places), "$v, $places places")
        }
    }

    @Test
    fun robotsAreListedByNameWithNumbersInOrder() {
        val names = listOf("PocketBot-10", "PocketBot-2", "alpha", "PocketBot-1", "PocketBot-02a", "PocketBot-2")
        assertEquals(listOf("PocketBot-1", "PocketBot-2", "PocketBot-2", "PocketBot-02a", "PocketBot-10", "alpha"),
            names.sortedWith(::compareNatural))
    }

    @Test
    fun anImportWithARefusedValueKeepsNothingAndAnUnreadableFileChangesNothing() = PanelFixture().use { f ->
        runBlocking {
            val robot = f.panel.connectEmbedded().single()
            val kpBefore = f.robotFloat("line_pid.kp")
            val dir = File("target/import-test").apply { mkdirs() }
            // line_pid.kp is fine, line_pid.ki is far outside its range: the robot refuses it.
            val half = File(dir, "half.json").apply { writeText("""{"line_pid": {"kp": 0.5, "ki": -7.0}}""") }
            robot.importSettings(half)
            until("a notice about the refusal") { f.panel.notices.value.any { "nothing of half.json was kept" in it.text } }
            assertEquals(kpBefore, f.robotFloat("line_pid.kp"), "the value written before the refusal was put back")

            val broken = File(dir, "broken.json").apply { writeText("""{"line_pid": {"kp": 0.5""") }
            robot.importSettings(broken)
            until("a notice about the broken file") { f.panel.notices.value.any { "broken.json" in it.text } }
            assertEquals(kpBefore, f.robotFloat("line_pid.kp"))

            val good = File(dir, "good.json").apply { writeText("""{"line_pid": {"kp": 0.5}}""") }
            robot.importSettings(good)
            until("the import") { f.robotFloat("line_pid.kp") == 0.5f }
        }
    }

    @Test
    fun aWorldThatDoesNotLoadIsReportedAndTheRunningEmulatorStays() = PanelFixture().use { f ->
        runBlocking {
            f.panel.connectEmbedded()
            val bad = File("target/bad-world.json").apply { writeText("""{"name": "oops", "widthM": """) }
            f.panel.restartEmulator(bad.path, 2)
            until("a notice") { f.panel.notices.value.any { "cannot start world" in it.text } }
            assertEquals("round", f.emulator.world.value.world.name)
            assertEquals(1, f.panel.robots.value.size, "the connected robot stays connected")

            f.panel.restartEmulator("straight", 2)
            until("two robots on the new world") { f.panel.robots.value.size == 2 && f.emulator.world.value.world.name == "straight" }
        }
    }

    @Test
    fun teleoperationKeepsTheRobotDrivingPastTheFailsafeUntilStopped() = PanelFixture(world = "straight").use { f ->
        runBlocking {
            val robot = f.panel.connectEmbedded().single()
            robot.drive(0.1, 0.1)
            delay(2500) // longer than the robot's default failsafe (1000 ms): the panel's repeats keep it going
            assertTrue(robot.robot.state.value.wheels.speedLeftMmps > 50, "wheels at ${robot.robot.state.value.wheels.speedLeftMmps} mm/s")
            robot.stop(immediate = false)
            until("standing still") { robot.robot.state.value.wheels.let { it.speedLeftMmps == 0 && it.speedRightMmps == 0 } }
        }
    }

    @Test
    fun anEditWhileTheLinkIsDownWaitsForItAndOneTheLinkCutsOffIsNotConfirmedRatherThanRefused() = PanelFixture().use { f ->
        runBlocking {
            val robot = f.panel.connectEmbedded().single()
            val link = robot.emulated!!
            link.disconnectLink()
            until("the loss is noticed") { robot.robot.connection.value != ConnectionState.Connected }
            robot.write("line_pid.kd", "0.375")
            val waiting = robot.edits.value["line_pid.kd"]
            assertIs<EditStatus.Pending>(waiting)
            assertTrue("sent when it is back" in describe(waiting, robot.robot.connection.value), describe(waiting, robot.robot.connection.value))
            link.reconnectLink()
            until("acknowledged after the reconnect") { robot.edits.value["line_pid.kd"] is EditStatus.Acknowledged }
            assertEquals(0.375f, f.robotFloat("line_pid.kd"))

            link.disconnectLink()
            until("the loss is noticed again") { robot.robot.connection.value != ConnectionState.Connected }
            robot.write("line_pid.kd", "0.5")
            f.panel.disconnect(robot) // the user gives up on the robot while the edit waits
            until("the edit ends") { robot.edits.value["line_pid.kd"] !is EditStatus.Pending }
            val cut = robot.edits.value["line_pid.kd"]
            assertIs<EditStatus.NotConfirmed>(cut, "the robot never refused it: $cut")
            assertTrue(describe(cut).startsWith("not confirmed: the link closed"), describe(cut))
            assertEquals(0.375f, f.robotFloat("line_pid.kd"), "nothing reached the robot")
        }
    }

    @Test
    fun theTrajectoryCsvHoldsTheOdometryAndTheTruePathOfAnEmulatedRobot() = PanelFixture(world = "straight").use { f ->
        runBlocking {
            val robot = f.panel.connectEmbedded().single()
            robot.robot.odometry.reset(robot.emulated!!.truePose)
            robot.robot.odometry.clearTrajectory()
            f.emulator.clearPaths()
            robot.robot.locomotion.enqueue(Movement.Straight(0.15, 0.2)).await()
            val end = robot.emulated!!.truePose
            until("the true path reaches the end") { f.emulator.truePath(robot.address)!!.points.value.last().pose.distanceTo(end) < 0.002 }
            val lines = f.panel.trajectoryCsv(robot).lines().filter { it.isNotBlank() }
            assertEquals("path,time_ms,x_m,y_m,heading_rad", lines.first())
            val byPath = lines.drop(1).map { it.split(',') }.groupBy({ it[0] }, { Pose(it[2].toDouble(), it[3].toDouble(), it[4].toDouble()) })
            assertEquals(setOf("odometry", "true"), byPath.keys)
            for ((path, poses) in byPath) {
                val length = poses.zipWithNext { a, b -> a.distanceTo(b) }.sum()
                assertTrue(abs(length - 0.15) < 0.01, "$path path is $length m long for a 0.15 m movement")
            }
            assertTrue(byPath.getValue("odometry").last().distanceTo(byPath.getValue("true").last()) < 0.01, "odometry ends where the robot is")
        }
    }
}

package org.pocketbot.examples

import kotlinx.coroutines.delay
import kotlinx.coroutines.launch
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.physics.Obb
import org.pocketbot.emulator.runSimulated
import org.pocketbot.emulator.world.Surface
import org.pocketbot.sdk.Fleet
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/** Thesis A.2 against the real firmware in the emulator, judged by its ground truth. */
class CooperativePushTest {
    @Test
    fun `two robots push the heavy box off the track together, never touch, and follow the line on`() =
        Emulator.local(robots = 2, world = "push").use { emu ->
            val currentIds = emu.robots.associate { it.id to ArrayList<Pair<Long, Int>>() } // (ms, current movement) at each change
            var overlapAt = -1L
            var steps = 0
            val report = emu.runSimulated(limit = 120.seconds) {
                // Ground truth after every 1 ms step: the movement each firmware runs, and whether two bodies overlap.
                val monitor = launch {
                    val a = Obb(); val b = Obb(); val out = DoubleArray(3)
                    val p = emu.config.robotParams
                    while (true) {
                        delay(1.milliseconds)
                        steps++
                        val ms = emu.time.inWholeMilliseconds
                        for (h in emu.robots) {
                            val id = h.state().locomotion.currentId
                            val log = currentIds.getValue(h.id)
                            if (log.lastOrNull()?.second != id) log += ms to id
                        }
                        val (r1, r2) = emu.robots.map { it.truePose }
                        a.set(r1.xM, r1.yM, r1.headingRad, p.lengthM / 2, p.widthM / 2)
                        b.set(r2.xM, r2.yM, r2.headingRad, p.lengthM / 2, p.widthM / 2)
                        if (overlapAt < 0 && a.overlap(b, out)) overlapAt = ms
                    }
                }
                val fleet = Fleet(this)
                try {
                    cooperativePush(fleet, emu.discoverer())
                } finally {
                    monitor.cancel()
                    fleet.disconnect()
                }
            }
            val box = emu.world.boxes.single()
            val clearance = emu.boxClearanceM()
            println("push: box ${"%.1f".format(clearance * 1000)} mm off the tape; pushes ${report.pushIds}; robot contacts ${emu.robotContacts}; $steps steps watched")
            assertTrue(clearance >= box.widthM, "the box is ${clearance * 1000} mm off the tape, less than its own width (${box.widthM * 1000} mm)")
            assertEquals(0L, emu.robotContacts, "robot bodies touched (ground truth, every step)")
            assertEquals(-1L, overlapAt, "robot bodies overlapped at $overlapAt ms")
            val starts = report.pushIds.map { (robot, pushId) ->
                currentIds.getValue(robot).firstOrNull { it.second == pushId }?.first ?: error("robot $robot never ran its push $pushId")
            }
            assertTrue(kotlin.math.abs(starts[0] - starts[1]) <= 1, "the pushes started at $starts ms: more than one firmware tick apart")
            // Both went on along the loop, round the corner the box blocked, on the line.
            val surface = Surface(emu.world)
            for (h in emu.robots) {
                val p = h.truePose
                assertTrue(surface.distanceToTape(p.xM, p.yM) < 0.006, "robot ${h.id} ended off the line at $p")
                assertTrue(p.yM > 0.25, "robot ${h.id} did not follow the loop round the corner: $p")
            }
        }

    @Test
    fun `make push ends with the box's clearance and the time it took`() {
        val lines = captureStdout { runMain("org.pocketbot.examples.CooperativePushKt") }
        val last = lines.last()
        val m = Regex("""box cleared: (\d+) mm off the tape in (\d+\.\d) s""").matchEntire(last)
        assertTrue(m != null, "last line: '$last'")
        assertTrue(m.groupValues[1].toInt() >= 40, "cleared only ${m.groupValues[1]} mm: $last")
    }
}

/** Runs the `main` of the example in file class [mainClass] (every example has one, so the name alone is ambiguous). */
fun runMain(mainClass: String, vararg args: String) {
    val cls = Class.forName(mainClass)
    val withArgs = cls.methods.firstOrNull { it.name == "main" && it.parameterCount == 1 }
    if (withArgs != null) withArgs.invoke(null, arrayOf(*args)) else cls.getMethod("main").invoke(null)
}

/** Runs [block] with System.out captured; returns the lines it printed. */
fun captureStdout(block: () -> Unit): List<String> {
    val original = System.out
    val bytes = java.io.ByteArrayOutputStream()
    System.setOut(java.io.PrintStream(bytes, true, Charsets.UTF_8))
    try {
        block()
    } finally {
        System.setOut(original)
    }
    return bytes.toString(Charsets.UTF_8).lines().filter { it.isNotBlank() }.also { it.forEach(original::println) }
}

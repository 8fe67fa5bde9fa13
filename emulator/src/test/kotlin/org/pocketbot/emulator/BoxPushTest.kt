package org.pocketbot.emulator

import org.pocketbot.sdk.Pose
import org.pocketbot.protocol.MoveStraight
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds

/** Thesis A.2: the heavy box is too much for one robot and not for two. */
class BoxPushTest {
    private fun push(robots: List<Pose>): Double = RealFirmware.emulator("box").use { emu ->
        val hosts = robots.map { TestHost(emu.addRobot(pose = it)) }
        emu.runFor(0.2.seconds)
        val before = emu.boxes().single()
        for (h in hosts) h.send(MoveStraight(1, 0.15f, 0.08f))
        repeat(16) { hosts.first().run(0.25.seconds); hosts.drop(1).forEach { it.send(org.pocketbot.protocol.Heartbeat, acked = false) } }
        val after = emu.boxes().single()
        assertEquals(0L, emu.robotContacts, "robots pushing side by side touched each other")
        hosts.forEach { it.close() }
        println("box pushed by ${robots.size} robot(s): moved ${"%.1f".format((after.xM - before.xM) * 1000)} mm; " +
            "robots at ${emu.robots.map { "%.3f".format(it.truePose.xM) }}")
        after.xM - before.xM
    }

    @Test
    fun `one robot cannot move the heavy box`() {
        val moved = push(listOf(Pose.ofDegrees(0.4, 0.2, 0.0)))
        assertTrue(moved < 0.001, "one robot moved the box ${moved * 1000} mm")
    }

    @Test
    fun `two robots pushing together move the heavy box`() {
        val moved = push(listOf(Pose.ofDegrees(0.4, 0.183, 0.0), Pose.ofDegrees(0.4, 0.217, 0.0)))
        assertTrue(moved > 0.02, "two robots moved the box only ${moved * 1000} mm")
    }

    @Test
    fun `robots driving at each other do not pass through each other`() = RealFirmware.emulator("straight").use { emu ->
        val a = TestHost(emu.addRobot(pose = Pose.ofDegrees(0.30, 0.25, 0.0)))
        val b = TestHost(emu.addRobot(pose = Pose.ofDegrees(0.40, 0.25, 180.0)))
        a.send(MoveStraight(1, 0.10f, 0.08f)); b.send(MoveStraight(1, 0.10f, 0.08f))
        repeat(8) { a.run(0.25.seconds); b.send(org.pocketbot.protocol.Heartbeat, acked = false) }
        val xa = a.robot.truePose.xM; val xb = b.robot.truePose.xM
        assertTrue(xb - xa >= 0.047, "robots overlap: centres ${xa} and ${xb} m, bodies are 48 mm long")
        assertTrue(emu.robotContacts > 0, "the robots met head on, yet no contact was counted")
        a.close(); b.close()
    }
}

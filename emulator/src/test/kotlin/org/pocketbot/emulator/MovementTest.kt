package org.pocketbot.emulator

import org.pocketbot.sdk.Pose
import org.pocketbot.protocol.MoveRotate
import org.pocketbot.protocol.MoveStraight
import kotlin.math.abs
import kotlin.math.cos
import kotlin.math.sin
import kotlin.test.Test
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds

/** Movements commanded over the protocol end where the issue says, in ground truth. */
class MovementTest {
    @Test
    fun `a 10 cm straight movement ends within 2 mm of 10 cm`() = RealFirmware.emulator("straight").use { emu ->
        val robot = emu.addRobot(pose = Pose.ofDegrees(0.3, 0.25, 0.0)) // off the line: the surface does not matter
        TestHost(robot).use { host ->
            emu.runFor(0.2.seconds)
            val start = robot.truePose
            host.send(MoveStraight(1, 0.10f, 0.10f))
            val done = host.runUntil(5.seconds) { robot.state().locomotion.finishedId == 1 }
            host.run(0.3.seconds) // let it come to rest
            val end = robot.truePose
            val h = Math.toRadians(start.headingDeg)
            val along = (end.xM - start.xM) * cos(h) + (end.yM - start.yM) * sin(h)
            println("straight 0.10 m: moved ${"%.2f".format(along * 1000)} mm, heading ${"%.2f".format(end.headingDeg)} deg, done=$done")
            assertTrue(done, "movement 1 did not finish in 5 s: ${robot.state().locomotion}")
            assertTrue(abs(along - 0.10) <= 0.002, "moved ${along * 1000} mm instead of 100 +- 2 mm")
        }
    }

    @Test
    fun `a 90 degree rotation ends within 3 degrees`() = RealFirmware.emulator("straight").use { emu ->
        val robot = emu.addRobot(pose = Pose.ofDegrees(0.3, 0.25, 0.0))
        TestHost(robot).use { host ->
            emu.runFor(0.2.seconds)
            val start = robot.truePose
            host.send(MoveRotate(2, 90f, 0.05f))
            val done = host.runUntil(5.seconds) { robot.state().locomotion.finishedId == 2 }
            host.run(0.3.seconds)
            val end = robot.truePose
            val turned = wrapDeg(end.headingDeg - start.headingDeg)
            println("rotate 90 deg: turned ${"%.2f".format(turned)} deg, done=$done")
            assertTrue(done, "movement 2 did not finish in 5 s: ${robot.state().locomotion}")
            assertTrue(abs(turned - 90) <= 3, "turned $turned deg instead of 90 +- 3")
        }
    }
}

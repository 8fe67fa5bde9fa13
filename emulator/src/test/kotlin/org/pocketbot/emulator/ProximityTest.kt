package org.pocketbot.emulator

import org.pocketbot.sdk.Pose
import org.pocketbot.protocol.IrReceived
import org.pocketbot.protocol.IrSend
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

/** IR proximity between robots and from obstacles, as the firmware reports it in robot_state. */
class ProximityTest {
    private val obstacle = 1
    private val robotSeen = 2

    @Test
    fun `two robots facing each other report each other's id on the front`() = RealFirmware.emulator("straight").use { emu ->
        val a = emu.addRobot(id = 3, pose = Pose.ofDegrees(0.3, 0.25, 0.0))
        val b = emu.addRobot(id = 8, pose = Pose.ofDegrees(0.4, 0.25, 180.0))
        emu.runFor(200.milliseconds)
        val pa = a.state().proximity; val pb = b.state().proximity
        assertEquals(8, pa.front.robotId, "robot 3 front: ${pa.front}")
        assertEquals(3, pb.front.robotId, "robot 8 front: ${pb.front}")
        assertTrue(pa.front.flags and robotSeen != 0 && pb.front.flags and robotSeen != 0, "robot flags: $pa / $pb")
        assertEquals(0, pa.rear.robotId, "nobody behind robot 3: ${pa.rear}")
        assertEquals(0, pb.rear.robotId, "nobody behind robot 8: ${pb.rear}")
    }

    @Test
    fun `a robot following another sees it in front, and is seen on the rear`() = RealFirmware.emulator("straight").use { emu ->
        val follower = emu.addRobot(id = 4, pose = Pose.ofDegrees(0.3, 0.25, 0.0))
        val leader = emu.addRobot(id = 5, pose = Pose.ofDegrees(0.38, 0.25, 0.0))
        emu.runFor(200.milliseconds)
        assertEquals(5, follower.state().proximity.front.robotId, "follower front: ${follower.state().proximity}")
        assertEquals(4, leader.state().proximity.rear.robotId, "leader rear: ${leader.state().proximity}")
    }

    @Test
    fun `a robot facing the box reports an obstacle, not a robot`() = RealFirmware.emulator("box").use { emu ->
        val r = emu.addRobot(id = 6, pose = Pose.ofDegrees(0.44, 0.2, 0.0)) // front at 0.464 m, box face at 0.48 m
        emu.runFor(200.milliseconds)
        val front = r.state().proximity.front
        assertTrue(front.flags and obstacle != 0, "no obstacle reported: $front")
        assertTrue(front.flags and robotSeen == 0, "a robot reported in front of the box: $front")
        assertEquals(0, front.robotId)
    }

    @Test
    fun `a robot with nothing around reports nothing`() = RealFirmware.emulator("straight").use { emu ->
        val r = emu.addRobot(pose = Pose.ofDegrees(0.3, 0.25, 0.0))
        emu.runFor(200.milliseconds)
        val p = r.state().proximity
        assertEquals(0, p.front.flags, "front: $p"); assertEquals(0, p.rear.flags, "rear: $p")
    }

    @Test
    fun `IR does not pass through a robot body - a payload reaches the robot in between, not the one hidden behind it`() =
        RealFirmware.emulator("straight").use { emu ->
            // In a line, 22 mm apart: without the body in between the last one's front receiver is in range of the
            // first one's LEDs (92 mm).
            val hidden = TestHost(emu.addRobot(id = 4, pose = Pose.ofDegrees(0.30, 0.25, 0.0)))
            val between = TestHost(emu.addRobot(id = 5, pose = Pose.ofDegrees(0.37, 0.25, 0.0)))
            val sender = TestHost(emu.addRobot(id = 6, pose = Pose.ofDegrees(0.44, 0.25, 0.0)))
            sender.send(IrSend(100, byteArrayOf(42)))
            sender.run(300.milliseconds)
            assertTrue(between.drain().filterIsInstance<IrReceived>().any { it.senderId == 6 }, "the robot right behind did not hear the payload")
            assertTrue(hidden.drain().filterIsInstance<IrReceived>().none { it.senderId == 6 }, "the payload passed through robot 5's body")
            listOf(hidden, between, sender).forEach { it.close() }
        }

    @Test
    fun `a box between two robots stops their IR - each sees the box, neither the other robot`() = RealFirmware.emulator("box").use { emu ->
        // Facing each other across the 40 mm box at x=0.5, front LEDs 72 mm apart: in range, but behind the box.
        val a = emu.addRobot(id = 3, pose = Pose.ofDegrees(0.44, 0.2, 0.0))
        val b = emu.addRobot(id = 8, pose = Pose.ofDegrees(0.56, 0.2, 180.0))
        repeat(20) {
            emu.runFor(20.milliseconds)
            for ((r, other) in listOf(a to 8, b to 3)) {
                val front = r.state().proximity.front
                assertTrue(front.robotId != other, "robot ${r.id} hears robot $other through the box: $front")
            }
        }
        assertTrue(a.state().proximity.front.flags and obstacle != 0 && b.state().proximity.front.flags and obstacle != 0, "both see the box")
    }

    @Test
    fun `an IR payload sent by one robot reaches the other robot's host`() = RealFirmware.emulator("straight").use { emu ->
        val a = TestHost(emu.addRobot(id = 3, pose = Pose.ofDegrees(0.3, 0.25, 0.0)))
        val b = TestHost(emu.addRobot(id = 8, pose = Pose.ofDegrees(0.4, 0.25, 180.0)))
        val payload = byteArrayOf(1, 2, 3, 4, 5, 6, 7)
        a.send(IrSend(100, payload))
        a.run(300.milliseconds)
        val heard = b.drain().filterIsInstance<IrReceived>()
        assertTrue(heard.isNotEmpty(), "robot 8's host got no ir_received; got ${b.packets.map { it::class.simpleName }.toSet()}")
        val m = heard.first()
        assertEquals(3, m.senderId); assertEquals(0, m.side, "heard on the front receiver")
        assertTrue(m.data.contentEquals(payload), "payload ${m.data.toList()}")
        a.close(); b.close()
    }
}

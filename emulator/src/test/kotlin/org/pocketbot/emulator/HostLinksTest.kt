package org.pocketbot.emulator

import org.pocketbot.emulator.link.NoFreeLinkException
import org.pocketbot.protocol.Driver
import org.pocketbot.protocol.DriverChange
import org.pocketbot.protocol.Error
import org.pocketbot.protocol.ErrorCode
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Goodbye
import org.pocketbot.protocol.HostRole
import org.pocketbot.protocol.LeaveQueue
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.MovementDone
import org.pocketbot.protocol.MovementOutcome
import org.pocketbot.protocol.SlipDecoder
import org.pocketbot.protocol.StateFull
import org.pocketbot.sdk.Pose
import org.pocketbot.sdk.transport.TransportLostException
import java.net.InetAddress
import java.net.Socket
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertIs
import kotlin.test.assertNotNull
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/** Several hosts on one emulated robot, each on a host link of its own, through the real firmware. */
class HostLinksTest {
    private fun robot(emu: Emulator): RobotHandle = emu.addRobot(pose = Pose.ofDegrees(0.3, 0.25, 0.0))

    @Test
    fun `each host gets a link of its own, one drives, the others watch and are told who drives`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robot(emu)
        TestHost(robot, session = 0xAAA).use { panel ->
            TestHost(robot, session = 0xBBB).use { cli ->
                assertEquals(2, robot.hostsConnected)
                val told = assertNotNull(cli.driver())
                assertEquals(HostRole.WATCH.code, told.role, "the second host watches")
                assertEquals("test@emulator", told.label, "and is told who drives")
                val seq = cli.send(MoveStraight(5, 0.05f, 0.1f))
                cli.run(20.milliseconds)
                val refused = cli.all<Error>().single { it.seq == seq }
                assertEquals(ErrorCode.NOT_DRIVER.code, refused.code)
                assertEquals(0, robot.state().locomotion.queueLength, "the watcher moved nothing")
                val moved = panel.send(MoveStraight(6, 0.02f, 0.1f))
                panel.runUntil(3.seconds) { cli.all<MovementDone>().isNotEmpty() }
                assertTrue(panel.ackOf(moved) != null, "the driver's movement ran")
                assertEquals(6, cli.all<MovementDone>().single().id, "the watcher sees its result too")
                assertTrue(cli.all<StateFull>().isNotEmpty() && panel.all<StateFull>().isNotEmpty(), "state to both")
            }
        }
    }

    @Test
    fun `more hosts than the robot has links are refused, in process and over TCP, with the reason`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robot(emu)
        val hosts = List(robot.hostLinks) { robot.openTransport() }
        val e = assertFailsWith<TransportLostException> { robot.openTransport() }
        assertEquals("emulator:1: all 3 host links of the robot are in use by other hosts", e.message)
        assertIs<NoFreeLinkException>(e.cause)
        val port = robot.startTcp(0)
        Socket(InetAddress.getLoopbackAddress(), port).use { s ->
            s.soTimeout = 5000
            val bytes = s.getInputStream().readBytes() // the answer, then the end of the stream
            val frames = ArrayList<ByteArray>()
            SlipDecoder().feed(bytes, onError = {}) { frames += it }
            val error = (Frames.decode(frames.single()) as FrameResult.Decoded).packet
            assertEquals(Error(ErrorCode.NO_FREE_LINK.code, 0, 0, 3), error)
        }
        hosts.first().close()
        emu.runFor(10.milliseconds)
        robot.openTransport().close() // a link came free
        hosts.drop(1).forEach { it.close() }
    }

    @Test
    fun `a goodbye sent just before the link closes still reaches the robot, which finishes the queue`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robot(emu)
        val start = robot.trueWheelDistances.leftM
        TestHost(robot).use { host ->
            host.send(MoveStraight(1, 0.20f, 0.1f))
            host.run(100.milliseconds)
            host.send(Goodbye(LeaveQueue.FINISH.code))
        } // closed at once: the goodbye is still on its way
        emu.runFor(4.seconds) // no host: far past the failsafe
        assertEquals(0.20, robot.trueWheelDistances.leftM - start, 0.005, "finished, not cut by the failsafe")
        TestHost(robot, session = 0x5EC).use { next ->
            assertEquals(HostRole.DRIVE.code, next.driver()?.role, "the drive was free")
        }
    }

    @Test
    fun `a take-over tells the old driver, whose commands are refused from then on`(): Unit = RealFirmware.emulator("straight").use { emu ->
        val robot = robot(emu)
        TestHost(robot, session = 0xAAA).use { panel ->
            TestHost(robot, session = 0xBBB, handshake = false).use { cli ->
                cli.hello(role = HostRole.TAKE_OVER)
                panel.run(20.milliseconds)
                val told = assertNotNull(panel.driver())
                assertEquals(HostRole.WATCH.code, told.role)
                assertEquals(DriverChange.TAKEN_OVER.code, told.change)
                val seq = panel.send(MoveStraight(9, 0.05f, 0.1f))
                panel.run(20.milliseconds)
                assertEquals(ErrorCode.NOT_DRIVER.code, panel.all<Error>().single { it.seq == seq }.code)
                val moved = cli.send(MoveStraight(10, 0.01f, 0.1f))
                cli.run(20.milliseconds)
                assertTrue(cli.ackOf(moved) != null, "the new driver's command runs")
            }
        }
    }
}

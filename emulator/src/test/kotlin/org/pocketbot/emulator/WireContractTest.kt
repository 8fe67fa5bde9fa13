package org.pocketbot.emulator

import org.pocketbot.sdk.Pose
import org.pocketbot.protocol.Ack
import org.pocketbot.protocol.Crc16
import org.pocketbot.protocol.ErrorCode
import org.pocketbot.protocol.Error as ErrorPacket
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Goodbye
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.HostRole
import org.pocketbot.protocol.LeaveQueue
import org.pocketbot.protocol.LoadDefaults
import org.pocketbot.protocol.MoveArc
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.MovementDone
import org.pocketbot.protocol.MovementLog
import org.pocketbot.protocol.MovementOutcome
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.ReadMovements
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.SaveSettings
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder
import org.pocketbot.protocol.Stop
import org.pocketbot.protocol.UpdateSettings
import java.net.InetAddress
import java.net.Socket
import java.nio.ByteBuffer
import java.nio.ByteOrder
import kotlin.math.abs
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertNotNull
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * The wire contract of docs/protocol.md, checked against the real firmware in the emulator: sessions and
 * duplicates, error answers and counters, refusals and their detail, movement results and the log, reset.
 */
class WireContractTest {
    private fun robotOffTheLine(emu: Emulator): RobotHandle = emu.addRobot(pose = Pose.ofDegrees(0.3, 0.25, 0.0))

    private fun trueDistance(r: RobotHandle): Double = r.trueWheelDistances.let { (it.leftM + it.rightM) / 2 }

    private fun TestHost.readMovements(): MovementLog {
        val seq = send(ReadMovements)
        check(runUntil(500.milliseconds) { ackOf(seq) != null }) { "read_movements not acknowledged" }
        return all<MovementLog>().last()
    }

    private fun TestHost.refusal(seq: Int): ErrorPacket? {
        drain()
        return received.firstOrNull { it.first == seq && it.second is ErrorPacket }?.second as ErrorPacket?
    }

    private fun fieldOffset(path: String) = SETTINGS_FIELDS.single { it.path == path }.offset

    private fun f32(v: Float) = ByteBuffer.allocate(4).order(ByteOrder.LITTLE_ENDIAN).putFloat(v).array()

    @Test
    fun `hello tells whether the session was resumed and the CRC of the settings`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robotOffTheLine(emu)
        TestHost(robot, session = 0xA11CEL, handshake = false).use { a ->
            val first = a.hello()
            assertEquals(0, first.sessionResumed, "a new session")
            assertEquals(TestHost.HELLO_SEQ, a.received.last { it.second is Hello }.first, "the answer carries the request's sequence number")
            assertEquals(Crc16.compute(robot.settingsBytes()), first.settingsCrc, "CRC of the settings in memory")
            assertEquals(1, a.hello().sessionResumed, "the same session again")
            a.send(UpdateSettings(fieldOffset("line_follow.speed_mps"), f32(0.2f)))
            a.run(20.milliseconds)
            val after = a.hello()
            assertEquals(Crc16.compute(robot.settingsBytes()), after.settingsCrc, "the CRC follows a change")
            assertTrue(after.settingsCrc != first.settingsCrc, "a change changes the CRC")
        }
        TestHost(robot, session = 0xB0BL, handshake = false).use { b -> assertEquals(0, b.hello(role = HostRole.TAKE_OVER).sessionResumed, "another host") }
        TestHost(robot, session = 0L, handshake = false).use { c ->
            assertEquals(0, c.hello(role = HostRole.TAKE_OVER).sessionResumed, "no session")
            assertEquals(0, c.hello(role = HostRole.TAKE_OVER).sessionResumed, "no session is never resumed")
        }
    }

    @Test
    fun `within a session only an identical frame is a retransmission`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robotOffTheLine(emu)
        TestHost(robot).use { host ->
            host.hello()
            val frame = Frames.encode(MoveStraight(1, 0.02f, 0.1f), 5)
            host.sendFrame(frame)
            host.sendFrame(frame) // the same bytes: acknowledged again, not executed
            host.send(MoveStraight(2, 0.03f, 0.1f), seq = 5) // the same seq with another payload: a new command
            host.run(20.milliseconds)
            assertEquals(3, host.all<Ack>().count { it.ackedType == MoveStraight.TYPE }, "every frame acknowledged")
            assertEquals(2, robot.state().locomotion.queueLength, "executed once each: ${robot.state().locomotion}")
            host.runUntil(3.seconds) { host.all<MovementDone>().size >= 2 }
            host.run(100.milliseconds)
            assertEquals(listOf(1, 2), host.all<MovementDone>().map { it.id })
        }
    }

    @Test
    fun `two hosts in turn with overlapping sequence numbers both get every command executed`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robotOffTheLine(emu)
        // Host B sends byte for byte the frames host A sent: in its own session they are new commands.
        val frames = (1..5).map { Frames.encode(MoveStraight(it, 0.01f, 0.1f), it) }
        for (session in listOf(0xAAAAL, 0xBBBBL)) {
            TestHost(robot, session = session).use { host ->
                host.hello()
                frames.forEach { host.sendFrame(it) }
                assertTrue(host.runUntil(200.milliseconds) { (1..5).all { host.ackOf(it) != null } }, "acks in session $session")
                // It leaves the robot to finish its queue (without the goodbye, the failsafe would end it).
                host.send(Goodbye(LeaveQueue.FINISH.code))
                host.run(20.milliseconds)
            }
        }
        TestHost(robot, session = 0xCCCCL).use { host ->
            host.hello(role = HostRole.WATCH)
            host.runUntil(5.seconds) { robot.state().locomotion.queueLength == 0 }
            host.run(400.milliseconds)
            val log = host.readMovements()
            assertEquals(10, log.count, "ten movements ended: $log")
            assertEquals(listOf(1, 2, 3, 4, 5, 1, 2, 3, 4, 5), log.ids.take(10))
            assertTrue(log.outcomes.take(10).all { it == MovementOutcome.FINISHED.code }, "all finished: ${log.outcomes}")
        }
    }

    @Test
    fun `frames that cannot be read are counted and answered at a limited rate`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robotOffTheLine(emu)
        TestHost(robot).use { host ->
            host.hello()
            val good = Frames.encode(SetSync(0, 100), 0)
            val badCrc = good.copyOf().also { it[it.size - 1] = (it[it.size - 1].toInt() xor 1).toByte() }
            host.sendFrame(badCrc)
            host.run(150.milliseconds)
            host.sendFrame(byteArrayOf(1, 2))
            host.run(150.milliseconds)
            host.sendFrame(ByteArray(130) { 0x11 })
            host.run(150.milliseconds)
            robot.hostSendRaw(byteArrayOf(0xC0.toByte(), 1, 0xDB.toByte(), 7, 2, 0xC0.toByte())) // a broken escape
            host.run(150.milliseconds)
            val answers = host.all<ErrorPacket>()
            assertEquals(
                listOf(ErrorCode.BAD_CRC, ErrorCode.TOO_SHORT, ErrorCode.TOO_LONG, ErrorCode.FRAMING),
                answers.map { ErrorCode.fromCode(it.code) },
            )
            assertEquals(listOf(good.size, 2, 130, 3), answers.map { it.detail }, "the frame lengths seen")
            assertTrue(answers.all { it.packetType == 0 && it.seq == 0 }, "type and seq cannot be trusted: $answers")
            val errors = robot.state().errors
            assertEquals(1, errors.crc)
            assertEquals(3, errors.framing)
            assertEquals(0, errors.rejected)

            // A burst: every one counted, at most one answer per 100 ms.
            repeat(30) { host.sendFrame(badCrc); emu.runFor(2.milliseconds) }
            host.run(20.milliseconds)
            assertEquals(31, robot.state().errors.crc)
            val burstAnswers = host.all<ErrorPacket>().size - answers.size
            assertTrue(burstAnswers in 1..1, "$burstAnswers answers to 30 bad frames in 80 ms")
        }
    }

    @Test
    fun `refused commands are counted under rejected and say why`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robotOffTheLine(emu)
        TestHost(robot).use { host ->
            host.hello()
            // A length the type does not allow: a move_straight of 4 bytes, CRC sound.
            val short = byteArrayOf(MoveStraight.TYPE.toByte(), 7, 4, 1, 0, 0, 0, 0, 0)
            val crc = Crc16.compute(short, 0, 7)
            short[7] = crc.toByte(); short[8] = (crc shr 8).toByte()
            host.sendFrame(short)
            host.send(MoveStraight(1, 0.1f, 0.1f), seq = 0) // acked commands need a seq
            val badSpeed = host.send(MoveArc(1, 0.1f, 45f, Float.NaN))
            host.run(20.milliseconds)
            val e7 = host.refusal(7)
            assertNotNull(e7); assertEquals(ErrorCode.BAD_LENGTH, ErrorCode.fromCode(e7.code)); assertEquals(4, e7.detail)
            val e0 = host.refusal(0)
            assertNotNull(e0); assertEquals(ErrorCode.BAD_SEQUENCE, ErrorCode.fromCode(e0.code)); assertEquals(MoveStraight.TYPE, e0.packetType)
            val eArg = host.refusal(badSpeed)
            assertNotNull(eArg); assertEquals(ErrorCode.BAD_ARGUMENT, ErrorCode.fromCode(eArg.code))
            assertEquals(10, eArg.detail, "the offset of speed_mps in move_arc")
            assertEquals(3, robot.state().errors.rejected)
            assertEquals(0, robot.state().errors.framing)
            assertEquals(0, robot.state().locomotion.queueLength, "nothing refused was executed")
        }
    }

    @Test
    fun `a header length that disagrees with the frame and a settings range off the fields are refused as documented`() =
        RealFirmware.emulator("straight").use { emu ->
            val robot = robotOffTheLine(emu)
            TestHost(robot).use { host ->
                host.hello()
                // The header says 10 bytes of payload, the frame carries 4; the CRC over what is there is sound.
                val frame = byteArrayOf(MoveStraight.TYPE.toByte(), 11, 10, 1, 0, 0, 0, 0, 0)
                val crc = Crc16.compute(frame, 0, 7)
                frame[7] = crc.toByte(); frame[8] = (crc shr 8).toByte()
                host.sendFrame(frame)
                // Two bytes into line_pid.kp: not on a field boundary.
                val offset = fieldOffset("line_pid.kp") + 2
                val range = host.send(UpdateSettings(offset, byteArrayOf(0, 0)))
                host.run(20.milliseconds)
                val e11 = host.refusal(11)
                assertNotNull(e11); assertEquals(ErrorCode.BAD_LENGTH, ErrorCode.fromCode(e11.code))
                assertEquals(10, e11.detail, "the length in the header")
                val eRange = host.refusal(range)
                assertNotNull(eRange); assertEquals(ErrorCode.SETTINGS_RANGE, ErrorCode.fromCode(eRange.code))
                assertEquals(offset, eRange.detail, "the offset of the refused update_settings")
                assertEquals(2, robot.state().errors.rejected, "both under rejected")
                assertEquals(0, robot.state().errors.framing)
            }
        }

    @Test
    fun `a TCP connect alone gets no hello, so a host begins with hello_request`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robotOffTheLine(emu)
        emu.runFor(100.milliseconds) // booted: the hello at reset went out before anyone listened
        val port = robot.startTcp(0)
        Socket(InetAddress.getLoopbackAddress(), port).use { s ->
            val decoder = SlipDecoder()
            val types = mutableListOf<Int>()
            val buf = ByteArray(4096)
            repeat(50) {
                emu.runFor(10.milliseconds)
                Thread.sleep(2) // the endpoint's threads carry the bytes
                while (s.getInputStream().available() > 0) {
                    val n = s.getInputStream().read(buf)
                    decoder.feed(buf, 0, n) { f -> (Frames.decode(f) as? FrameResult.Decoded)?.let { types += it.packet.type } }
                }
            }
            assertTrue(Hello.TYPE !in types, "no hello in 500 ms after the connect: $types")
            s.getOutputStream().write(Slip.encode(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 5L), 3)))
            s.getOutputStream().flush()
            var answered = false
            repeat(50) {
                if (answered) return@repeat
                emu.runFor(10.milliseconds)
                Thread.sleep(2)
                while (s.getInputStream().available() > 0) {
                    val n = s.getInputStream().read(buf)
                    decoder.feed(buf, 0, n) { f -> if ((Frames.decode(f) as? FrameResult.Decoded)?.packet is Hello) answered = true }
                }
            }
            assertTrue(answered, "the hello_request is answered")
        }
    }

    @Test
    fun `an update_settings without data is refused by its size`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robotOffTheLine(emu)
        TestHost(robot).use { host ->
            host.hello()
            // UpdateSettings refuses to be built without data, so the frame is put together by hand.
            val frame = byteArrayOf(UpdateSettings.TYPE.toByte(), 9, 3, 0, 0, 0, 0, 0)
            val crc = Crc16.compute(frame, 0, 6)
            frame[6] = crc.toByte(); frame[7] = (crc shr 8).toByte()
            host.sendFrame(frame)
            host.run(20.milliseconds)
            val e = host.refusal(9)
            assertNotNull(e, "answered")
            assertEquals(ErrorCode.BAD_LENGTH, ErrorCode.fromCode(e.code))
            assertEquals(3, e.detail)
            assertEquals(1, robot.state().errors.rejected)
        }
    }

    @Test
    fun `movements report finished, stopped and dropped with what they did`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robotOffTheLine(emu)
        TestHost(robot).use { host ->
            host.hello()
            val d0 = trueDistance(robot)
            host.send(MoveStraight(1, 0.05f, 0.1f))
            host.runUntil(3.seconds) { host.all<MovementDone>().isNotEmpty() }
            val finished = host.all<MovementDone>().single()
            assertEquals(MovementOutcome.FINISHED.code, finished.outcome)
            assertEquals(trueDistance(robot) - d0, finished.done.toDouble(), 0.002, "done against the ground truth")

            val d1 = trueDistance(robot)
            host.send(MoveStraight(2, 0.5f, 0.1f))
            host.send(MoveStraight(3, 0.5f, 0.1f))
            host.send(MoveStraight(4, 0.5f, 0.1f))
            host.run(500.milliseconds)
            host.send(Stop(1))
            host.runUntil(1.seconds) { host.all<MovementDone>().size >= 4 }
            val results = host.all<MovementDone>().drop(1)
            assertEquals(listOf(2, 3, 4), results.map { it.id })
            assertEquals(
                listOf(MovementOutcome.STOPPED, MovementOutcome.DROPPED, MovementOutcome.DROPPED),
                results.map { MovementOutcome.fromCode(it.outcome) },
            )
            assertEquals(trueDistance(robot) - d1, results[0].done.toDouble(), 0.002, "stopped after what it drove")
            assertEquals(listOf(0f, 0f), results.drop(1).map { it.done }, "dropped before they started")
        }
    }

    @Test
    fun `a 30 cm straight cut by a 2 s outage ends as failsafe with how far it went, read back after reconnecting`() =
        RealFirmware.emulator("straight").use { emu ->
            val robot = robotOffTheLine(emu)
            val session = 0x0DDBA11L
            val start: Double
            TestHost(robot, session = session).use { host ->
                host.hello()
                start = trueDistance(robot)
                host.send(MoveStraight(7, 0.30f, 0.10f))
                host.send(MoveStraight(8, 0.10f, 0.10f))
                host.run(1.seconds)
            }
            robot.disconnectLink() // out of range for 2 s: the default failsafe (1000 ms) stops the robot
            emu.runFor(2.seconds)
            robot.reconnectLink()
            val truth = trueDistance(robot) - start
            TestHost(robot, session = session).use { host ->
                assertEquals(1, host.hello().sessionResumed, "the robot still serves this host's session")
                val log = host.readMovements()
                assertEquals(2, log.count, "both movements ended: $log")
                assertEquals(listOf(7, 8), log.ids.take(2))
                assertEquals(listOf(MovementOutcome.FAILSAFE.code, MovementOutcome.FAILSAFE.code), log.outcomes.take(2))
                println("failsafe after an outage: done ${"%.2f".format(log.done[0] * 1000)} mm, ground truth ${"%.2f".format(truth * 1000)} mm")
                assertTrue(truth > 0.1 && truth < 0.3, "the outage cut the movement: drove ${truth * 1000} mm")
                assertEquals(truth, log.done[0].toDouble(), 0.005, "done against the ground truth")
                assertEquals(0f, log.done[1], "the queued one never started")
                assertEquals(0, log.queueLength)
            }
        }

    @Test
    fun `a reset power-cycles the firmware, keeps saved settings, says hello and clears the log`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robotOffTheLine(emu)
        val speedAt = fieldOffset("line_follow.speed_mps")
        fun speedSetting() = ByteBuffer.wrap(robot.settingsBytes(), speedAt, 4).order(ByteOrder.LITTLE_ENDIAN).float
        TestHost(robot).use { host ->
            host.hello()
            host.send(UpdateSettings(speedAt, f32(0.2f)))
            val saved = host.send(SaveSettings)
            host.runUntil(100.milliseconds) { host.ackOf(saved) != null }
            host.send(UpdateSettings(speedAt, f32(0.25f))) // not saved
            host.send(MoveStraight(1, 0.5f, 0.1f))
            host.send(MoveStraight(2, 0.5f, 0.1f))
            host.run(300.milliseconds)
            val hellosBefore = host.all<Hello>().size
            val timeBefore = robot.state().time.timeMs
            robot.reset()
            host.run(50.milliseconds)
            val hello = host.all<Hello>().drop(hellosBefore).singleOrNull()
            assertNotNull(hello, "hello at reset")
            assertEquals(0, hello.sessionResumed)
            assertEquals(0, host.received.last { it.second is Hello }.first, "the hello at reset carries sequence 0")
            assertEquals(0.2f, speedSetting(), "the saved settings came back from the EEPROM")
            assertEquals("PocketBot-1", robot.name)
            assertTrue(robot.state().time.timeMs < timeBefore, "the robot's clock restarted")
            assertEquals(0, robot.state().locomotion.queueLength, "the queue is gone")
            assertEquals(0, host.readMovements().count, "the log is gone")
            assertEquals(0, host.hello().sessionResumed, "after a reset no session is served")
            host.send(LoadDefaults)
            host.run(20.milliseconds)
        }
    }

    @Test
    fun `the TCP endpoint bounds what a host floods it with, and the robot still answers`() = RealFirmware.emulator("straight").use { emu ->
        val robot = robotOffTheLine(emu)
        val port = robot.startTcp(0)
        Socket(InetAddress.getLoopbackAddress(), port).use { s ->
            s.soTimeout = 10_000
            val flood = ByteArray(1 shl 20) // no END: one endless broken frame
            s.getOutputStream().write(flood)
            s.getOutputStream().flush()
            // The endpoint reads on its own thread: wait (wall clock, no assertion on it) until all of it is in.
            val limit = robot.link.bufferBytes
            val deadline = System.currentTimeMillis() + 20_000
            while (robot.linkBytesOverflowed < flood.size - limit && System.currentTimeMillis() < deadline) Thread.sleep(5)
            assertTrue(robot.linkBytesOverflowed >= flood.size - limit, "overflow counted: ${robot.linkBytesOverflowed}")
            emu.runFor(300.milliseconds) // what the buffer held reaches the robot at 115200 Bd
            // The robot booted in that run and sent its own hello (sequence 0): only the answer to this
            // request (its sequence) shows that the request got through the flood's remains.
            val requestSeq = 7
            s.getOutputStream().write(Slip.encode(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 3L), requestSeq)))
            s.getOutputStream().flush()
            val decoder = SlipDecoder()
            var hello: Hello? = null
            val buf = ByteArray(4096)
            var simMs = 0
            while (hello == null && simMs < 200) {
                emu.runFor(10.milliseconds); simMs += 10
                while (s.getInputStream().available() > 0) {
                    val n = s.getInputStream().read(buf)
                    decoder.feed(buf, 0, n) { f ->
                        val decoded = Frames.decode(f) as? FrameResult.Decoded
                        if (decoded?.seq == requestSeq) (decoded.packet as? Hello)?.let { hello = it }
                    }
                }
                if (hello == null) Thread.sleep(1) // the endpoint's threads carry the bytes
            }
            assertNotNull(hello, "no answer to the hello request within 200 ms of simulated time after the flood")
            assertTrue(robot.state().errors.framing >= 1, "the flood ended as one over-long frame")
        }
    }
}

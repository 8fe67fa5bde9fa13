package org.pocketbot.sdk.it

import kotlinx.coroutines.async
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.launch
import kotlinx.coroutines.yield
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.link.LinkSettings
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementHandle
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport
import kotlin.math.abs
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/** Movements on the real firmware: exactly once across faults, and together on several robots. */
class MovementIntegrationTest {
    private val step = 0.03
    private val speed = 0.2

    @Test
    fun movementsFinishExactlyOnceAcrossAShortDisconnect() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        val start = sim.trueWheelDistances
        val states = mutableListOf<ConnectionState>()
        val watcher = launch { robot.connection.collect { states += it } }
        yield()
        val handles = mutableListOf<MovementHandle>()
        repeat(2) { handles += robot.locomotion.enqueue(Movement.Straight(step, speed)) }
        // The third goes out and the link dies before its ack can come back: it is in flight during the outage,
        // which is shorter than the robot's failsafe (default 1000 ms).
        val inFlight = async { robot.locomotion.enqueue(Movement.Straight(step, speed)) }
        yield()
        sim.disconnectLink()
        val outage = launch {
            delay(300)
            sim.reconnectLink()
        }
        handles += inFlight.await()
        // Issued while the link is down (or just back): they wait for the reconnect.
        repeat(3) { handles += robot.locomotion.enqueue(Movement.Straight(step, speed)) }
        robot.locomotion.awaitIdle()
        outage.join()
        watcher.cancel()
        assertTrue(handles.all { it.await().outcome == MovementOutcome.FINISHED }, "${handles.map { it.await() }}")
        assertTrue(states.any { it is ConnectionState.Lost }, "the outage must have been noticed: $states")
        assertEquals(ConnectionState.Connected, robot.connection.value)
        assertTrue(robot.linkStats.value.reconnects >= 1)
        val end = sim.trueWheelDistances
        val driven = (end.leftM - start.leftM + end.rightM - start.rightM) / 2
        assertTrue(abs(driven - 6 * step) < 0.012, "drove $driven m for 6 x $step m: a movement was lost or repeated")
        robot.close()
    }

    @Test
    fun movementExecutedButUnackedWhenTheLinkDiesIsNotExecutedAgain() = withEmulator { emu ->
        val sim = emu.robots.single()
        var dropped = false
        // Swallow the ack of the third move_straight and take the link down at that moment: the robot has queued
        // the movement, the host does not know it. After the reconnect the SDK finds it in the robot's queue.
        val device = AckDroppingDevice(emu.discoverer().discover().first(), dropNth = 3) {
            dropped = true
            sim.disconnectLink()
        }
        val robot = device.connect(this, itOptions())
        val start = sim.trueWheelDistances
        val reconnect = launch {
            while (!dropped) delay(1)
            delay(300)
            sim.reconnectLink()
        }
        val handles = (1..5).map { robot.locomotion.enqueue(Movement.Straight(step, speed)) }
        robot.locomotion.awaitIdle()
        reconnect.join()
        assertTrue(dropped, "the ack was never dropped")
        assertTrue(handles.all { it.await().outcome == MovementOutcome.FINISHED }, "${handles.map { it.await() }}")
        assertTrue(robot.linkStats.value.reconnects >= 1)
        val end = sim.trueWheelDistances
        val driven = (end.leftM - start.leftM + end.rightM - start.rightM) / 2
        assertTrue(abs(driven - 5 * step) < 0.012, "drove $driven m for 5 x $step m: the unacked move ran twice or never")
        robot.close()
    }

    @Test
    fun movementsFinishExactlyOnceOnALossyCorruptingLink() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        val start = sim.trueWheelDistances
        sim.link = LinkSettings(lossRate = 0.004, corruptionRate = 0.004)
        val handles = (1..6).map { robot.locomotion.enqueue(Movement.Straight(step, speed)) }
        robot.locomotion.awaitIdle()
        sim.link = LinkSettings()
        assertTrue(handles.all { it.await().outcome == MovementOutcome.FINISHED }, "${handles.map { it.await() }}")
        val end = sim.trueWheelDistances
        val driven = (end.leftM - start.leftM + end.rightM - start.rightM) / 2
        assertTrue(abs(driven - 6 * step) < 0.012, "drove $driven m for 6 x $step m: a movement was lost or repeated")
        robot.close()
    }

    @Test
    fun odometryFollowsTheFirmwareEncoderCountsThroughRotationAndArc() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        val t0 = sim.truePose
        val w0 = sim.trueWheelDistances
        val e0 = sim.state().encoders
        robot.state.first { it.time.timeMs > 0 }
        // Reset and move at once: the reset must count from now, not from the next state (mid-rotation).
        robot.odometry.reset(t0)
        robot.locomotion.enqueue(Movement.Rotate(90.0, 0.1))
        robot.locomotion.enqueue(Movement.Arc(0.05, -90.0, 0.1))
        robot.locomotion.awaitIdle()
        val e1 = sim.state().encoders
        robot.state.first { it.encoders.left == e1.left && it.encoders.right == e1.right }
        val pose = robot.odometry.pose.value

        // Exact: the heading is the thesis formula over the firmware's own total counts (theta = 2 pi r / (l T) (N2 - N1)).
        val d = robot.settings.geometry.wheelDiameterM.value
        val l = robot.settings.geometry.wheelBaseM.value
        val pulses = robot.settings.encoder.pulsesPerRev.value.toDouble()
        val expected = t0.headingRad + Math.PI * d / pulses / l * ((e1.right - e0.right) - (e1.left - e0.left))
        assertEquals(expected, pose.headingRad, 1e-9, "odometry heading from the total encoder counts")

        // Against the ground truth it can only be as good as the counts: single-channel encoders take their
        // direction from the motor PWM, so a reversal while a wheel still rolls miscounts a few pulses.
        val t = sim.truePose
        val wheels = sim.trueWheelDistances
        val rolledHeading = t0.headingRad + ((wheels.rightM - w0.rightM) - (wheels.leftM - w0.leftM)) / l
        val err = pose.distanceTo(t)
        println("rotate+arc: odometry $pose, true $t, position error ${"%.1f".format(err * 1000)} mm, " +
            "counted vs rolled heading ${"%.2f".format(Math.toDegrees(pose.headingRad - rolledHeading))} deg")
        assertTrue(err < 0.01, "odometry $pose vs true $t: ${err * 1000} mm")
        robot.close()
    }

    @Test
    fun fleetStartsMovementsOnThreeRobotsAtTheSameMoment() = withEmulator(robots = 3, world = "round") { emu ->
        val fleet = Fleet(this, itOptions())
        // Each device's transport notes the simulated time a move_straight frame leaves the SDK.
        val sentAt = HashMap<String, Long>()
        val devices = emu.discoverer().discover().toList().map { TimedDevice(it) { address -> sentAt.putIfAbsent(address, emu.timeTicks) } }
        val robots = fleet.connectAll(devices)
        assertEquals(3, robots.size)
        val sims = robots.map { emu.handleOf(it) }
        val base = sims.map { it.trueWheelDistances.leftM }
        val startedAt = LongArray(3) { -1 }
        val watcher = launch {
            while (startedAt.any { it < 0 }) {
                sims.forEachIndexed { i, s -> if (startedAt[i] < 0 && s.trueWheelDistances.leftM - base[i] > 1e-5) startedAt[i] = emu.timeTicks }
                delay(1)
            }
        }
        val handles = fleet.enqueueTogether(robots.associateWith { Movement.Straight(0.05, 0.1) })
        fleet.awaitIdle()
        watcher.join()
        assertTrue(handles.values.all { it.await().outcome == MovementOutcome.FINISHED })
        assertEquals(3, sentAt.size)
        val ticksPerMs = 32_000.0
        val sdkSkewMs = (sentAt.values.max() - sentAt.values.min()) / ticksPerMs
        val wheelSkewMs = (startedAt.max() - startedAt.min()) / ticksPerMs
        println("fleet start skew (simulated): frames left the SDK within $sdkSkewMs ms; wheels started within $wheelSkewMs ms")
        assertEquals(0.0, sdkSkewMs, "the three move frames must leave the SDK in the same simulated millisecond")
        // The wheels add the link's byte time (each frame ~1.5 ms at 115200 Bd) and motor friction noise.
        assertTrue(wheelSkewMs <= 10.0, "wheels started $wheelSkewMs ms apart (ticks ${startedAt.toList()})")
        fleet.close()
        assertTrue(robots.all { it.connection.value is ConnectionState.Closed })
    }

    @Test
    fun twoHostsInTurnWithOverlappingSequenceNumbersGetEveryCommandExecuted() = withEmulator { emu ->
        val sim = emu.robots.single()
        val device = emu.discoverer().discover().first()
        val start = sim.trueWheelDistances
        // Each host numbers its commands from 1: the second host's move reuses the first host's sequence numbers
        // with other contents. The robot must execute it, not take it for a retransmission.
        val first = device.connect(this, itOptions())
        first.locomotion.enqueue(Movement.Straight(0.02, speed)).await()
        first.disconnect()
        val second = device.connect(this, itOptions())
        val r = second.locomotion.enqueue(Movement.Straight(0.05, speed)).await()
        assertEquals(MovementOutcome.FINISHED, r.outcome)
        val end = sim.trueWheelDistances
        val driven = (end.leftM - start.leftM + end.rightM - start.rightM) / 2
        assertTrue(abs(driven - 0.07) < 0.006, "drove $driven m for 0.02 + 0.05 m: the second host's move was swallowed")
        second.close()
    }
}

/** A device whose transports report each `move_straight` frame they send to [onMove] with the device's address. */
private class TimedDevice(private val inner: RobotDevice, private val onMove: (String) -> Unit) : RobotDevice {
    override val name: String get() = inner.name
    override val address: String get() = inner.address
    override suspend fun open(): Transport {
        val t = inner.open()
        return object : Transport by t {
            override suspend fun send(frame: ByteArray) {
                if (frame[0] == MoveStraight.TYPE.toByte()) onMove(address)
                t.send(frame)
            }
        }
    }
}

/** A device whose transports swallow the ack of the [dropNth] `move_straight` and call [onDrop] instead. */
private class AckDroppingDevice(private val inner: RobotDevice, private val dropNth: Int, private val onDrop: () -> Unit) : RobotDevice {
    private var moveAcks = 0
    override val name: String get() = inner.name
    override val address: String get() = inner.address
    override suspend fun open(): Transport {
        val t = inner.open()
        return object : Transport by t {
            override val incoming: kotlinx.coroutines.channels.ReceiveChannel<ByteArray> get() = filtered
            private val filtered = kotlinx.coroutines.channels.Channel<ByteArray>(kotlinx.coroutines.channels.Channel.UNLIMITED)

            init {
                // Runs on the emulator's stepping thread as frames arrive (no extra coroutine, no wall clock).
                kotlinx.coroutines.GlobalScope.launch(kotlinx.coroutines.Dispatchers.Unconfined) {
                    try {
                        for (f in t.incoming) {
                            if (f[0] == org.pocketbot.protocol.Ack.TYPE.toByte() && f[3] == MoveStraight.TYPE.toByte() && ++moveAcks == dropNth) {
                                onDrop()
                                continue
                            }
                            filtered.send(f)
                        }
                        filtered.close()
                    } catch (e: Throwable) {
                        filtered.close(e)
                    }
                }
            }

            override fun close() {
                t.close()
                filtered.close()
            }
        }
    }
}

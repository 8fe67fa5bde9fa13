package org.pocketbot.sdk.it

import kotlinx.coroutines.async
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import org.pocketbot.sdk.connect
import kotlinx.coroutines.launch
import kotlinx.coroutines.yield
import org.pocketbot.sdk.MovementHandle
import kotlinx.coroutines.flow.toList
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.link.LinkSettings
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementResult
import kotlin.math.abs
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/** Movements on the real firmware: exactly once across faults, and together on several robots. */
class MovementIntegrationTest {
    private val step = 0.03
    private val speed = 0.2

    @Test
    fun movementsFinishExactlyOnceAcrossAForcedDisconnect() = withEmulator { emu ->
        val robot = connectAll(emu).single()
        val sim = emu.handleOf(robot)
        robot.settings.link.failsafeTimeoutMs.set(5000) // the outage below must not trip the robot's failsafe
        val start = sim.trueWheelDistances
        val states = mutableListOf<ConnectionState>()
        val watcher = launch { robot.connection.collect { states += it } }
        yield()
        val handles = mutableListOf<MovementHandle>()
        repeat(2) { handles += robot.locomotion.enqueue(Movement.Straight(step, speed)) }
        // The third goes out and the link dies before its ack can come back: it is in flight during the outage.
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
        assertTrue(handles.all { it.result() == MovementResult.FINISHED })
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
        val outage = java.util.concurrent.atomic.AtomicBoolean(false)
        // Swallow the ack of the third move_straight and take the link down at that moment: the robot has queued
        // the movement, the host does not know it. After the reconnect the SDK sends it again with the same
        // sequence number; the firmware must re-ack it without queuing it a second time.
        val device = AckDroppingDevice(emu.discoverer().discover().first(), dropNth = 3) {
            outage.set(true)
            sim.disconnectLink()
            Thread { Thread.sleep(300); sim.reconnectLink() }.start()
        }
        val robot = device.connect(this, itOptions())
        robot.settings.link.failsafeTimeoutMs.set(5000)
        val start = sim.trueWheelDistances
        val handles = (1..5).map { robot.locomotion.enqueue(Movement.Straight(step, speed)) }
        robot.locomotion.awaitIdle()
        assertTrue(outage.get(), "the ack was never dropped")
        assertTrue(handles.all { it.result() == MovementResult.FINISHED })
        assertTrue(robot.linkStats.value.reconnects >= 1)
        assertTrue(robot.linkStats.value.retransmissions >= 1, "the unacked move must have been sent again")
        val end = sim.trueWheelDistances
        val driven = (end.leftM - start.leftM + end.rightM - start.rightM) / 2
        assertTrue(abs(driven - 5 * step) < 0.012, "drove $driven m for 5 x $step m: the retransmitted move ran twice")
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
        assertTrue(handles.all { it.result() == MovementResult.FINISHED })
        val end = sim.trueWheelDistances
        val driven = (end.leftM - start.leftM + end.rightM - start.rightM) / 2
        assertTrue(abs(driven - 6 * step) < 0.012, "drove $driven m for 6 x $step m: a movement was lost or repeated")
        println("lossy link: ${robot.linkStats.value}")
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
        robot.odometry.reset(org.pocketbot.sdk.Pose(t0.x, t0.y, Math.toRadians(t0.headingDeg)))
        robot.locomotion.enqueue(Movement.Rotate(90.0, 0.1))
        robot.locomotion.enqueue(Movement.Arc(0.05, -90.0, 0.1))
        robot.locomotion.awaitIdle()
        delay(400) // the robot comes to a standstill: no more counts
        val e1 = sim.state().encoders
        kotlinx.coroutines.withTimeout(2000) { robot.state.first { it.encoders == e1 } }
        val pose = robot.odometry.pose.value

        // Exact: the heading is the thesis formula over the firmware's own total counts (theta = 2 pi r / (l T) (N2 - N1)).
        val d = robot.settings.geometry.wheelDiameterM.value.toDouble()
        val l = robot.settings.geometry.wheelBaseM.value.toDouble()
        val pulses = robot.settings.encoder.pulsesPerRev.value.toDouble()
        val expected = Math.toRadians(t0.headingDeg) + Math.PI * d / pulses / l * ((e1.right - e0.right) - (e1.left - e0.left))
        assertEquals(expected, pose.headingRad, 1e-9, "odometry heading from the total encoder counts")

        // Against the ground truth it can only be as good as the counts: single-channel encoders take their
        // direction from the motor PWM, so a reversal while a wheel still rolls miscounts a few pulses.
        val t = sim.truePose
        val wheels = sim.trueWheelDistances
        val rolledHeading = Math.toRadians(t0.headingDeg) + ((wheels.rightM - w0.rightM) - (wheels.leftM - w0.leftM)) / l
        val err = Math.hypot(pose.xM - t.x, pose.yM - t.y)
        println("rotate+arc: odometry $pose, true $t, position error ${"%.1f".format(err * 1000)} mm, " +
            "counted vs rolled heading ${"%.2f".format(Math.toDegrees(pose.headingRad - rolledHeading))} deg")
        assertTrue(err < 0.01, "odometry $pose vs true $t: ${err * 1000} mm")
        robot.close()
    }

    @Test
    fun fleetStartsMovementsOnThreeRobotsAtTheSameMoment() = withEmulator(robots = 3, world = "round") { emu ->
        // Robots on Dispatchers.Default (no scope): each sends from its own worker, not all from the test's thread.
        val fleet = Fleet(options = itOptions())
        // Each device's transport notes when a move_straight frame leaves the SDK (wall clock).
        val sentAt = java.util.concurrent.ConcurrentHashMap<String, Long>()
        val devices = emu.discoverer().discover().toList().map { TimedDevice(it, sentAt) }
        val robots = fleet.connectAll(devices)
        assertEquals(3, robots.size)
        val sims = robots.map { emu.handleOf(it) }
        val base = sims.map { it.trueWheelDistances.leftM }
        val startedAt = LongArray(3) { -1 }
        val watcher = async(kotlinx.coroutines.Dispatchers.IO) {
            while (startedAt.any { it < 0 }) {
                val now = emu.timeTicks
                sims.forEachIndexed { i, s -> if (startedAt[i] < 0 && s.trueWheelDistances.leftM - base[i] > 1e-5) startedAt[i] = now }
                Thread.sleep(0, 200_000)
            }
        }
        val handles = fleet.enqueueTogether(robots.associateWith { Movement.Straight(0.05, 0.1) })
        fleet.awaitIdle()
        watcher.await()
        assertTrue(handles.values.all { it.result() == MovementResult.FINISHED })
        val sdkSkewMs = (sentAt.values.max() - sentAt.values.min()) / 1e6
        val wheelSkewMs = (startedAt.max() - startedAt.min()) / 32_000.0
        println("fleet start skew: frames left the SDK within ${"%.3f".format(sdkSkewMs)} ms; wheels started within ${"%.1f".format(wheelSkewMs)} ms (simulated)")
        assertEquals(3, sentAt.size)
        assertTrue(sdkSkewMs <= 5.0, "the move frames left the SDK $sdkSkewMs ms apart")
        // The wheels add the emulator's own spread (motor friction noise, stepping batches under load).
        assertTrue(wheelSkewMs <= 50.0, "wheels started $wheelSkewMs ms apart (ticks ${startedAt.toList()})")
        fleet.close()
        assertTrue(robots.all { it.connection.value is ConnectionState.Closed })
    }
}

/** A device whose transports record the wall-clock time a `move_straight` frame is handed to the link. */
private class TimedDevice(private val inner: RobotDevice, private val sentAt: MutableMap<String, Long>) : RobotDevice {
    override val name: String get() = inner.name
    override val address: String get() = inner.address
    override suspend fun open(): Transport {
        val t = inner.open()
        return object : Transport by t {
            override suspend fun send(frame: ByteArray) {
                if (frame[0] == MoveStraight.TYPE.toByte()) sentAt.putIfAbsent(address, System.nanoTime())
                t.send(frame)
            }
        }
    }
}

private suspend fun org.pocketbot.sdk.MovementHandle.result(): MovementResult = await()

/** A device whose transports swallow the ack of the [dropNth] `move_straight` and call [onDrop] instead. */
private class AckDroppingDevice(private val inner: RobotDevice, private val dropNth: Int, private val onDrop: () -> Unit) : RobotDevice {
    private var moveAcks = 0
    override val name: String get() = inner.name
    override val address: String get() = inner.address
    override suspend fun open(): Transport {
        val t = inner.open()
        val frames = kotlinx.coroutines.channels.Channel<ByteArray>(kotlinx.coroutines.channels.Channel.UNLIMITED)
        val pump = kotlinx.coroutines.CoroutineScope(kotlinx.coroutines.Dispatchers.IO).launch {
            try {
                for (f in t.incoming) {
                    if (f[0] == org.pocketbot.protocol.Ack.TYPE.toByte() && f[3] == MoveStraight.TYPE.toByte() && ++moveAcks == dropNth) {
                        onDrop()
                        continue
                    }
                    frames.send(f)
                }
                frames.close()
            } catch (e: kotlinx.coroutines.CancellationException) {
                throw e
            } catch (e: Throwable) {
                frames.close(e)
            }
        }
        return object : Transport by t {
            override val incoming: kotlinx.coroutines.channels.ReceiveChannel<ByteArray> get() = frames
            override fun close() {
                pump.cancel()
                t.close()
                frames.close()
            }
        }
    }
}

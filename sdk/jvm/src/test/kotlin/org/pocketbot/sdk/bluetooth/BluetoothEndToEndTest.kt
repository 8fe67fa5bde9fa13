package org.pocketbot.sdk.bluetooth

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.async
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.filter
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.junit.jupiter.api.AfterAll
import org.junit.jupiter.api.AfterEach
import org.junit.jupiter.api.BeforeAll
import org.junit.jupiter.api.Test
import org.junit.jupiter.api.TestInstance
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.EmulatorConfig
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.emulator.Speed
import org.pocketbot.emulator.WheelDistances
import org.pocketbot.emulator.bluetooth.VirtualBluetooth
import org.pocketbot.emulator.firmware.FirmwareImage
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.MovementResult
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.StateUpdate
import org.pocketbot.sdk.SyncMode
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.it.itOptions
import org.pocketbot.sdk.it.valueIn
import org.pocketbot.sdk.transport.TcpFraming
import org.pocketbot.sdk.transport.TcpRobotDevice
import java.net.InetSocketAddress
import kotlin.math.abs
import kotlin.test.assertEquals
import kotlin.test.assertNotNull
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds
import kotlin.time.TimeSource

/**
 * The robot's own Bluetooth end to end: the HCI build of the firmware in the emulator drives its own virtual
 * controller over H4 (115200 Bd through the link model); the gateway pages it by address, finds its services by SDP
 * and opens RFCOMM or the framed L2CAP channel; the SDK's own TCP transports carry the whole protocol. Real time
 * (Bumble's timers are wall-clock), one Bumble process for the class, controllers power-cycled between tests.
 */
@TestInstance(TestInstance.Lifecycle.PER_CLASS)
class BluetoothEndToEndTest {
    private lateinit var bt: VirtualBluetooth

    @BeforeAll
    fun startControllers() { bt = VirtualBluetooth.start(controllers = 2) }

    @AfterAll
    fun stopControllers() { bt.close() }

    @AfterEach
    fun powerCycleControllers() { bt.controllers.forEach { bt.reset(it.index) } }

    @Test
    fun overRfcommTheSdkRunsTheWholeProtocol() = withRobots(1) { emu -> wholeProtocol(emu.robots[0], connect(0, TcpFraming.SLIP)) }

    @Test
    fun overTheFramedL2capChannelTheSdkRunsTheWholeProtocol() =
        withRobots(1) { emu -> wholeProtocol(emu.robots[0], connect(0, TcpFraming.LENGTH_PREFIXED)) }

    @Test
    fun twoRobotsAtOnceOneOverEachChannel() = withRobots(2) { emu ->
        val a = connect(0, TcpFraming.SLIP)
        val b = connect(1, TcpFraming.LENGTH_PREFIXED)
        val moves = listOf(a to emu.robots[0], b to emu.robots[1]).map { (robot, sim) ->
            async { drive(robot, sim, Movement.Straight(0.06, 0.1)) }
        }
        for (m in moves) assertTruthful(m.await(), MovementOutcome.FINISHED)
        assertEquals(listOf(1, 2), listOf(a.identity.robotId, b.identity.robotId))
        a.close(); b.close()
    }

    @Test
    fun whenTheRadioLinkDropsTheFailsafeStopsTheRobotAndTheSdkTellsTheTruth() = withRobots(1) { emu ->
        val robot = connect(0, TcpFraming.LENGTH_PREFIXED)
        val sim = emu.robots[0]
        val start = sim.trueWheelDistances
        val handle = robot.locomotion.enqueue(Movement.Straight(0.30, 0.1))
        delay(1.seconds)
        bt.drop(bt.controllers[0].address, outOfReach = 2.seconds)
        val result = handle.await()
        assertEquals(MovementOutcome.FAILSAFE, result.outcome, "the robot stopped on its own while out of reach")
        val drove = travel(start, sim)
        assertTrue(drove in 0.10..0.22, "drove $drove m of 0.30 before the failsafe")
        assertTrue(abs(assertNotNull(result.done) - drove) < 0.005, "reported ${result.done} m, ground truth $drove m")
        robot.connection.first { it == ConnectionState.Connected }
        assertTruthful(drive(robot, sim, Movement.Straight(0.03, 0.1)), MovementOutcome.FINISHED)
        robot.close()
    }

    @Test
    fun aclFragmentedTowardsTheRobotIsReassembled() {
        H4Proxy(bt.controllers[0].h4, fragment = 7).use { proxy ->
            withRobots(1, wire = { proxy.endpoint }) { emu ->
                for (framing in TcpFraming.values()) {
                    val robot = connect(0, framing)
                    // update_settings carries a 16-byte name: an L2CAP PDU far longer than 7 bytes.
                    robot.settings.identity.name.set("Fragmented-$framing".take(15))
                    assertEquals(robot.settings.identity.name.value, emu.robots[0].name)
                    assertTruthful(drive(robot, emu.robots[0], Movement.Rotate(45.0, 0.05)), MovementOutcome.FINISHED, toleranceDeg = 2.0)
                    robot.close()
                }
            }
            assertTrue(proxy.aclPacketsCut.get() > 10, "the proxy cut ${proxy.aclPacketsCut.get()} ACL packets")
        }
    }

    @Test
    fun garbageAndALostByteOnTheH4WireAreSurvived() {
        H4Proxy(bt.controllers[0].h4).use { proxy ->
            withRobots(1, wire = { proxy.endpoint }) { emu ->
                val robot = connect(0, TcpFraming.LENGTH_PREFIXED)
                val sim = emu.robots[0]
                robot.reflector.set(SyncMode.FULL, 20.milliseconds)
                proxy.injectGarbage(ByteArray(40) { (it * 37 + 5).toByte() })
                delay(3.seconds)
                proxy.dropAByte()
                delay(3.seconds)
                // The robot saw both, reset its controller and took the host back; the SDK is connected again.
                val errors = sim.state().errors
                assertTrue(errors.btWire + errors.btTimeouts >= 2 && errors.btResets >= 2, "the robot counts what the wire did: $errors")
                robot.connection.first { it == ConnectionState.Connected }
                assertTruthful(drive(robot, sim, Movement.Straight(0.04, 0.1)), MovementOutcome.FINISHED)
                robot.settings.linePid.kp.set(1.25)
                assertEquals(1.25, valueIn(sim.settingsBytes(), "line_pid.kp"))
                // The SDK's mirror says what the robot counted.
                val counted = sim.state().errors.btResets
                robot.stateUpdates.first { it.kind == StateUpdate.Kind.FULL && robot.state.value.errors.btResets == counted }
                robot.close()
            }
        }
    }

    @Test
    fun aControllerResetMidMovementIsRecoveredAndReportedTruthfully() = withRobots(1) { emu ->
        val robot = connect(0, TcpFraming.SLIP)
        val sim = emu.robots[0]
        val start = sim.trueWheelDistances
        val handle = robot.locomotion.enqueue(Movement.Straight(0.20, 0.1))
        delay(800.milliseconds)
        bt.reset(1)
        val result = handle.await()
        val drove = travel(start, sim)
        // The controller answered on as before: the robot's keep-alive alone found it power-cycled and reset it.
        val errors = sim.state().errors
        assertTrue(errors.btResets == 1 && errors.btTimeouts == 0 && errors.btWire == 0, "the robot's counters: $errors")
        assertTrue(result.outcome == MovementOutcome.FINISHED || result.outcome == MovementOutcome.FAILSAFE, "outcome $result")
        assertTrue(abs(assertNotNull(result.done) - drove) < 0.005, "reported ${result.done} m, ground truth $drove m")
        assertTruthful(drive(robot, sim, Movement.Straight(0.03, 0.1)), MovementOutcome.FINISHED)
        robot.close()
    }

    /** Handshake, a settings write checked in the robot's memory, full state at the link's pace, a movement. */
    private suspend fun wholeProtocol(sim: RobotHandle, robot: Robot) {
        assertEquals(sim.id, robot.identity.robotId)
        assertEquals(sim.name, robot.identity.name)
        robot.settings.linePid.kp.set(1.5)
        assertEquals(1.5, valueIn(sim.settingsBytes(), "line_pid.kp"))

        robot.reflector.set(SyncMode.FULL, 20.milliseconds)
        val first = robot.stateUpdates.filter { it.kind == StateUpdate.Kind.FULL }.first()
        val t0 = TimeSource.Monotonic.markNow()
        val before = robot.linkStats.value.fullStates
        delay(1.seconds)
        val rate = (robot.linkStats.value.fullStates - before) / t0.elapsedNow().inWholeMilliseconds.toDouble() * 1000
        // A full state every 20 ms fills about 60 % of the robot's 115200 Bd UART, Bluetooth framing and all.
        assertTrue(rate > 45, "full states at $rate/s, asked for 50/s (first at robot time ${first.timeMs} ms)")
        assertEquals(0, robot.linkStats.value.dropped, "no frame may be dropped on a sound link")

        assertTruthful(drive(robot, sim, Movement.Straight(0.08, 0.1)), MovementOutcome.FINISHED)
        robot.close()
    }

    private class Driven(val result: MovementResult, val truth: Double)

    private suspend fun drive(robot: Robot, sim: RobotHandle, movement: Movement): Driven {
        val start = sim.trueWheelDistances
        val result = robot.locomotion.enqueue(movement).await()
        delay(400.milliseconds) // the robot settles: coasting counts in the result
        val end = sim.trueWheelDistances
        val truth = if (movement is Movement.Rotate) Math.toDegrees((end.rightM - start.rightM - (end.leftM - start.leftM)) / WHEEL_BASE_M)
        else travel(start, sim)
        return Driven(result, truth)
    }

    /** The result says [outcome] and what the robot really did, within 5 mm (or [toleranceDeg] for a rotation). */
    private fun assertTruthful(d: Driven, outcome: MovementOutcome, toleranceDeg: Double = 0.0) {
        assertEquals(outcome, d.result.outcome, "outcome: ${d.result}")
        val done = assertNotNull(d.result.done)
        val tolerance = if (toleranceDeg > 0) toleranceDeg else 0.005
        assertTrue(abs(done - d.truth) < tolerance, "reported $done, ground truth ${d.truth}")
    }

    private fun travel(start: WheelDistances, sim: RobotHandle): Double {
        val end = sim.trueWheelDistances
        return (end.leftM - start.leftM + end.rightM - start.rightM) / 2
    }

    /**
     * Robots running the HCI firmware on real time, robot i wired to controller i, or to what [wire] makes of its
     * H4 endpoint; [block] runs on real time too, at most a minute.
     */
    private fun <T> withRobots(
        n: Int,
        wire: (InetSocketAddress) -> InetSocketAddress = { it },
        block: suspend CoroutineScope.(Emulator) -> T,
    ): T = Emulator.local(n, config = EmulatorConfig(firmware = FirmwareImage.compiledHci())).use { emu ->
        emu.robots.forEachIndexed { i, r -> r.attachH4(wire(bt.controllers[i].h4)) }
        emu.start(Speed.Realtime(1.0))
        runBlocking(Dispatchers.Default) { withTimeout(60.seconds) { block(emu) } }
    }

    /**
     * Connects the SDK to robot [index] through the gateway's RFCOMM ([TcpFraming.SLIP]) or L2CAP endpoint, as soon
     * as the robot's stack has brought its controller up (pages fail until then).
     */
    private suspend fun CoroutineScope.connect(index: Int, framing: TcpFraming): Robot {
        val bridge = bt.bridge(bt.controllers[index].address)
        val at = if (framing == TcpFraming.SLIP) bridge.rfcomm else bridge.l2cap
        val device = TcpRobotDevice(at.hostString, at.port, framing = framing)
        val deadline = TimeSource.Monotonic.markNow() + 10.seconds
        while (true) {
            try {
                return device.connect(this, itOptions())
            } catch (e: Exception) {
                if (deadline.hasPassedNow()) throw AssertionError("robot ${index + 1} not reachable over Bluetooth in 10 s", e)
                delay(100.milliseconds)
            }
        }
    }

    private companion object {
        const val WHEEL_BASE_M = 0.026
    }
}

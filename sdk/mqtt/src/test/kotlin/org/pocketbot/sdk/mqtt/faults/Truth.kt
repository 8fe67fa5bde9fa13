package org.pocketbot.sdk.mqtt.faults

import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.withTimeout
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.emulator.WheelDistances
import org.pocketbot.protocol.LocoMode
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.MovementHandle
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.mqtt.BrokerClient
import org.pocketbot.sdk.mqtt.BrokerOptions
import org.pocketbot.sdk.mqtt.BrokerRobotDevice
import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import kotlin.math.abs
import kotlin.test.assertEquals
import kotlin.test.assertNotNull
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/*
 * What the fault tests check against the emulator's ground truth. Every scene drives a 30 cm straight at 0.1 m/s on
 * the "straight" world and cuts a path 1 s into it for longer than the robot's link failsafe (1000 ms, the default).
 */

/** The movement every fault test cuts: 3 s long, cut 1 s in. */
internal val CUT_MOVEMENT = Movement.Straight(0.30, 0.1)

/** How far the robot's wheels went from [from] to now, on average. */
internal fun RobotHandle.drivenSince(from: WheelDistances): Double {
    val now = trueWheelDistances
    return (now.leftM - from.leftM + now.rightM - from.rightM) / 2
}

/** The robot stands still, stopped by its own failsafe. */
internal suspend fun assertStoppedByFailsafe(sim: RobotHandle, why: String) {
    val before = sim.trueWheelDistances
    delay(200.milliseconds)
    assertTrue(abs(sim.drivenSince(before)) < 0.0005, "$why: the robot still moves")
    assertEquals(LocoMode.FAILSAFE, sim.state().locomotion.mode, why)
}

/**
 * The movement [handle] started at [start] was cut by the failsafe: the handle ended FAILSAFE (or LOST) and reports
 * what the robot really drove, and the client's robot says it stands by its failsafe.
 */
internal suspend fun assertCutByFailsafe(robot: Robot, sim: RobotHandle, start: WheelDistances, handle: MovementHandle) {
    val result = handle.await()
    withTimeout(2.seconds) { robot.locomotion.state.first { robot.locomotion.mode == org.pocketbot.sdk.LocoMode.FAILSAFE } }
    val trueM = sim.drivenSince(start)
    println("cut movement: $result; ground truth $trueM m")
    assertTrue(result.outcome == MovementOutcome.FAILSAFE || result.outcome == MovementOutcome.LOST, "$result")
    // Stopped 1 s after the host's last packet, which left at most a heartbeat (1/3 s) before the cut 1 s in: about
    // 0.2 m; the upper bound leaves 0.6 s for a loaded machine to make the cut late, and is still short of 0.30 m.
    assertTrue(trueM in 0.10..0.26, "drove $trueM m of 0.30")
    val done = assertNotNull(result.done, "$result")
    assertTrue(abs(done - trueM) < 0.005, "reported $done m, ground truth $trueM m")
}

/** After a fault the robot drives again, and a movement runs exactly once. */
internal suspend fun assertNextMovementRunsOnce(robot: Robot, sim: RobotHandle) {
    val before = sim.trueWheelDistances
    val next = robot.locomotion.enqueue(Movement.Straight(0.05, 0.1)).await()
    assertEquals(MovementOutcome.FINISHED, next.outcome, "$next")
    delay(300.milliseconds) // anything executed twice would move it on
    assertEquals(0.05, sim.drivenSince(before), 0.003, "the next movement ran once")
}

/** The robot of gateway [gateway] once [client] has heard of it. */
internal suspend fun BrokerClient.robotOf(gateway: String): BrokerRobotDevice = withTimeout(10.seconds) {
    discoverer().discover().first { (it as BrokerRobotDevice).gateway == gateway } as BrokerRobotDevice
}

/** Options to reach [broker] as [user] over TLS through [proxy] (a path the test can cut). */
internal fun MosquittoBroker.optionsVia(proxy: CutProxy, user: String): BrokerOptions =
    BrokerOptions("mqtts://127.0.0.1:${proxy.port}") {
        username = user
        password = password(user).toCharArray()
        trustedCertificates = caFile
    }

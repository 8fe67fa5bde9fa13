package org.pocketbot.sdk

import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.plus
import kotlinx.coroutines.test.TestScope
import kotlin.coroutines.ContinuationInterceptor
import kotlin.random.Random
import kotlin.time.Duration.Companion.milliseconds

/** Options for scripted robots: a private cache, no state packets unless a test asks (no silence watchdog). */
fun testOptions(
    syncMode: SyncMode = SyncMode.NONE,
    cache: SettingsCache? = InMemorySettingsCache(),
    commandRetries: Int = 8,
    reconnect: ReconnectPolicy = ReconnectPolicy { initialDelay = 10.milliseconds; maxDelay = 100.milliseconds },
): RobotOptions = RobotOptions {
    this.syncMode = syncMode
    settingsCache = cache
    this.commandRetries = commandRetries
    this.reconnect = reconnect
}

/** The test's own virtual-time scheduler, as the runtime of the SDK's work: tests run on simulated time. */
fun TestScope.runtime(): RobotRuntime = RobotRuntime(coroutineContext[ContinuationInterceptor] as CoroutineDispatcher, Random(42))

/** A scope for robots and fleets that ends with the test, on the test's virtual time. */
fun TestScope.robotScope(): CoroutineScope = backgroundScope + runtime()

suspend fun TestScope.connect(peer: ScriptedRobot, options: RobotOptions = testOptions()): Robot =
    peer.device.connect(robotScope(), options)

/** Floats compared as float32 (on Kotlin/JS a Float literal is a double until it is encoded). */
fun assertF32(expected: Float, actual: Float, message: String? = null) =
    kotlin.test.assertEquals(expected.toRawBits(), actual.toRawBits(), message ?: "expected $expected, was $actual")

/** Packets compared by their wire bytes. */
fun assertSamePacket(expected: org.pocketbot.protocol.Packet, actual: org.pocketbot.protocol.Packet) =
    kotlin.test.assertContentEquals(
        org.pocketbot.protocol.Frames.encode(expected, 0), org.pocketbot.protocol.Frames.encode(actual, 0), "expected $expected, was $actual",
    )

/** The offset of the setting [name] in the settings struct, from the protocol definition. */
fun offsetOf(name: String): Int = org.pocketbot.protocol.SETTINGS_FIELDS.single { it.path == name }.offset

/** The wire state a scripted robot starts from: all zero, robot time 0. */
val WIRE_EMPTY: org.pocketbot.protocol.RobotState =
    org.pocketbot.protocol.RobotState.decode(ByteArray(org.pocketbot.protocol.ProtocolInfo.STATE_SIZE), 0)

/** [this] state with some groups replaced (state classes have no copy: fields may be added). */
fun org.pocketbot.protocol.RobotState.with(
    time: org.pocketbot.protocol.StateTime = this.time,
    encoders: org.pocketbot.protocol.StateEncoders = this.encoders,
    power: org.pocketbot.protocol.StatePower = this.power,
    proximity: org.pocketbot.protocol.StateProximity = this.proximity,
    locomotion: org.pocketbot.protocol.StateLocomotion = this.locomotion,
): org.pocketbot.protocol.RobotState = org.pocketbot.protocol.RobotState(
    time = time, encoders = encoders, wheels = wheels, line = line, lineFollow = lineFollow, proximity = proximity,
    colour = colour, accel = accel, power = power, indicators = indicators, locomotion = locomotion, track = track, errors = errors,
)

/** [this] state at robot time [timeMs]. */
fun org.pocketbot.protocol.RobotState.withTime(timeMs: Long): org.pocketbot.protocol.RobotState =
    with(time = org.pocketbot.protocol.StateTime(timeMs, time.tickMaxUs, time.overruns, time.lastOverrunMs))

/** Waits for the loss of [robot]'s link to be noticed, then for the reconnect. */
suspend fun awaitReconnect(robot: Robot) {
    robot.connection.first { it is ConnectionState.Lost || it is ConnectionState.Reconnecting }
    robot.connection.first { it == ConnectionState.Connected }
}

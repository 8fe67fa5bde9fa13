package org.pocketbot.sdk

import kotlinx.coroutines.test.TestScope
import org.pocketbot.protocol.SyncMode
import kotlin.time.Duration.Companion.milliseconds

/** Options for scripted robots: a private cache, no state packets unless a test asks (no silence watchdog). */
fun testOptions(
    syncMode: SyncMode = SyncMode.NONE,
    cache: SettingsCache? = InMemorySettingsCache(),
    commandRetries: Int = 8,
    reconnect: ReconnectPolicy = ReconnectPolicy(initialDelay = 10.milliseconds, maxDelay = 100.milliseconds),
): RobotOptions = RobotOptions(syncMode = syncMode, settingsCache = cache, commandRetries = commandRetries, reconnect = reconnect)

suspend fun TestScope.connect(peer: ScriptedRobot, options: RobotOptions = testOptions()): Robot =
    peer.device.connect(backgroundScope, options)

/** Floats compared as float32 (on Kotlin/JS a Float literal is a double until it is encoded). */
fun assertF32(expected: Float, actual: Float, message: String? = null) =
    kotlin.test.assertEquals(expected.toRawBits(), actual.toRawBits(), message ?: "expected $expected, was $actual")

/** Packets compared by their wire bytes. */
fun assertSamePacket(expected: org.pocketbot.protocol.Packet, actual: org.pocketbot.protocol.Packet) =
    kotlin.test.assertContentEquals(
        org.pocketbot.protocol.Frames.encode(expected, 0), org.pocketbot.protocol.Frames.encode(actual, 0), "expected $expected, was $actual",
    )

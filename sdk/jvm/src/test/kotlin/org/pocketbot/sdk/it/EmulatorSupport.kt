package org.pocketbot.sdk.it

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.emulator.Speed
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.connect
import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds

/** Options for emulated robots: a private settings cache per test, so tests do not see each other's settings. */
fun itOptions(): RobotOptions = RobotOptions(settingsCache = InMemorySettingsCache())

/**
 * Runs [block] against an embedded emulator with [robots] robots in real time (the SDK's timeouts are wall-clock,
 * the robot's failsafe is simulated time: real time keeps them in step).
 */
fun withEmulator(
    robots: Int = 1,
    world: String = "straight",
    timeout: Duration = 60.seconds,
    block: suspend CoroutineScope.(Emulator) -> Unit,
) {
    Emulator.local(robots = robots, world = world).use { emu ->
        emu.start(Speed.Realtime(1.0))
        try {
            runBlocking { withTimeout(timeout) { block(emu) } }
        } finally {
            emu.stop()
        }
    }
}

/** Connects every robot of [emu] (in discovery order). */
suspend fun CoroutineScope.connectAll(emu: Emulator, options: RobotOptions = itOptions()): List<Robot> =
    emu.discoverer().discover().toList().map { it.connect(this, options) }

/** The emulator's robot behind [robot]. */
fun Emulator.handleOf(robot: Robot): RobotHandle = robot(robot.identity.robotId)

/** Asserts that every settings field of [robot]'s mirror equals the robot's own settings bytes [onRobot]. */
fun assertMirrors(robot: Robot, onRobot: ByteArray) {
    val buf = java.nio.ByteBuffer.wrap(onRobot).order(java.nio.ByteOrder.LITTLE_ENDIAN)
    for (f in org.pocketbot.protocol.SETTINGS_FIELDS) {
        fun at(i: Int): Any = when (f.type) {
            org.pocketbot.protocol.FieldType.U8 -> buf.get(f.offset + i).toInt() and 0xFF
            org.pocketbot.protocol.FieldType.I8 -> buf.get(f.offset + i).toInt()
            org.pocketbot.protocol.FieldType.U16 -> buf.getShort(f.offset + 2 * i).toInt() and 0xFFFF
            org.pocketbot.protocol.FieldType.I16 -> buf.getShort(f.offset + 2 * i).toInt()
            org.pocketbot.protocol.FieldType.I32 -> buf.getInt(f.offset + 4 * i)
            org.pocketbot.protocol.FieldType.U32 -> buf.getInt(f.offset + 4 * i).toLong() and 0xFFFF_FFFFL
            org.pocketbot.protocol.FieldType.F32 -> buf.getFloat(f.offset + 4 * i)
            org.pocketbot.protocol.FieldType.CHAR -> error("text")
        }
        val expected: Any = when {
            f.type == org.pocketbot.protocol.FieldType.CHAR ->
                String(onRobot, f.offset, f.count).substringBefore('\u0000')
            f.count > 1 -> List(f.count) { at(it) }
            else -> at(0)
        }
        kotlin.test.assertEquals(expected, robot.settings.field(f.path)!!.value, "settings mirror of ${f.path}")
    }
}

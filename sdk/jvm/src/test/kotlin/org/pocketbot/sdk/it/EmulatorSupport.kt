package org.pocketbot.sdk.it

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.toList
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.emulator.runSimulated
import org.pocketbot.protocol.FieldType
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.connect
import java.nio.ByteBuffer
import java.nio.ByteOrder
import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds

/** Options for emulated robots: the defaults users get, with a private settings cache per test. */
fun itOptions(): RobotOptions = RobotOptions { settingsCache = InMemorySettingsCache() }

/**
 * Runs [block] against an embedded emulator with [robots] robots on simulated time: the SDK's clock is the
 * emulator's, so timeouts, heartbeats and the robot's failsafe are in step, the run repeats exactly, and it goes as
 * fast as the CPU allows. [limit] is simulated time.
 */
fun <T> withEmulator(
    robots: Int = 1,
    world: String = "straight",
    limit: Duration = 120.seconds,
    block: suspend CoroutineScope.(Emulator) -> T,
): T = Emulator.local(robots = robots, world = world).use { emu -> emu.runSimulated(limit) { block(emu) } }

/** Connects every robot of [emu] (in discovery order). */
suspend fun CoroutineScope.connectAll(emu: Emulator, options: RobotOptions = itOptions()): List<Robot> =
    emu.discoverer().discover().toList().map { it.connect(this, options) }

/** The emulator's robot behind [robot]. */
fun Emulator.handleOf(robot: Robot): RobotHandle = robots.single { it.address == robot.identity.address }

/** The value of the setting [name] in the robot's own settings bytes [onRobot], as the SDK's mirror types it. */
fun valueIn(onRobot: ByteArray, name: String): Any {
    val f = SETTINGS_FIELDS.single { it.path == name }
    val buf = ByteBuffer.wrap(onRobot).order(ByteOrder.LITTLE_ENDIAN)
    fun at(i: Int): Any = when (f.type) {
        FieldType.U8 -> buf.get(f.offset + i).toInt() and 0xFF
        FieldType.I8 -> buf.get(f.offset + i).toInt()
        FieldType.U16 -> buf.getShort(f.offset + 2 * i).toInt() and 0xFFFF
        FieldType.I16 -> buf.getShort(f.offset + 2 * i).toInt()
        FieldType.I32 -> buf.getInt(f.offset + 4 * i)
        FieldType.U32 -> buf.getInt(f.offset + 4 * i).toLong() and 0xFFFF_FFFFL
        FieldType.F32 -> buf.getFloat(f.offset + 4 * i).toDouble()
        FieldType.CHAR -> error("text")
    }
    return when {
        f.type == FieldType.CHAR -> String(onRobot, f.offset, f.count).substringBefore('\u0000')
        f.count > 1 -> List(f.count) { at(it) }
        else -> at(0)
    }
}

/** Asserts that every setting of [robot]'s mirror equals the robot's own settings bytes [onRobot]. */
fun assertMirrors(robot: Robot, onRobot: ByteArray) {
    for (f in SETTINGS_FIELDS) {
        val mirrored = robot.settings[f.path]!!.value
        val expected = valueIn(onRobot, f.path)
        // the SDK's enums and the wire's come from one schema: the same names
        val same = if (mirrored is Enum<*>) org.pocketbot.protocol.SyncMode.fromCode(expected as Int).name == mirrored.name else expected == mirrored
        kotlin.test.assertTrue(same, "settings mirror of ${f.path}: $mirrored, robot holds $expected")
    }
}

package org.pocketbot.sdk

import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.distinctUntilChanged
import kotlinx.coroutines.flow.map
import org.pocketbot.protocol.FieldType
import org.pocketbot.protocol.SettingsFieldInfo
import org.pocketbot.protocol.UpdateSettings
import org.pocketbot.sdk.internal.readNumber
import org.pocketbot.sdk.internal.writeNumber

/**
 * One leaf of the robot's settings struct (thesis 9.6), e.g. `robot.settings.linePid.kp`.
 *
 * [value] is the value the robot confirmed last. [set] sends only this field (`update_settings` with its offset and
 * bytes), suspends until the robot acknowledged it, retransmits on timeout, and throws [SettingRefusedException] when
 * the robot refuses it (the robot is the referee of [min]..[max]).
 */
public sealed class SettingField<T> constructor(
    private val robot: Robot,
    /** Offset, type, count, range, unit and documentation, from the protocol definition. */
    public val info: SettingsFieldInfo,
) {
    /** Dotted path in the protocol definition, e.g. `line_pid.kp`. */
    public val path: String get() = info.path

    /** Unit of the value (`m/s`, `ms`, ...), empty when it has none. */
    public val unit: String get() = info.unit

    /** Lowest value the robot accepts, null when unbounded. */
    public val min: Double? get() = info.min

    /** Highest value the robot accepts, null when unbounded. */
    public val max: Double? get() = info.max

    /** The value the robot confirmed last (read at connect, then every acknowledged write). */
    public val value: T get() = decode(robot.settingsBytes)

    /** [value] now and after every change. */
    public val changes: Flow<T> get() = robot.settings.values.map { decode(robot.settingsBytes) }.distinctUntilChanged()

    /**
     * Writes [value] to the robot; suspends until it acknowledged, then [value] reflects it.
     *
     * @throws SettingRefusedException when the robot refuses the value.
     * @throws IllegalArgumentException when [value] cannot be encoded in the field's wire type at all.
     */
    public suspend fun set(value: T) {
        val bytes = ByteArray(info.size)
        encode(value, bytes)
        try {
            robot.command(UpdateSettings(info.offset, bytes))
        } catch (e: CommandRefusedException) {
            throw SettingRefusedException(path, value, e.packetType, e.rawCode, e.detail)
        }
        robot.serial { robot.settingsWritten(info.offset, bytes) }
    }

    internal abstract fun decode(settings: ByteArray): T
    internal abstract fun encode(value: T, out: ByteArray)

    override fun toString(): String = "$path = $value${if (unit.isEmpty()) "" else " $unit"}"
}

/** A settings field holding a real number (f32). */
public class FloatSetting internal constructor(robot: Robot, info: SettingsFieldInfo) : SettingField<Float>(robot, info) {
    init {
        require(info.type == FieldType.F32 && info.count == 1) { "${info.path} is not a float" }
    }

    override fun decode(settings: ByteArray): Float = readNumber(settings, info.offset, info.type).toFloat()
    override fun encode(value: Float, out: ByteArray) = writeNumber(out, 0, info.type, value, path)
}

/** A settings field holding an integer (u8, i8, u16, i16, i32). */
public class IntSetting internal constructor(robot: Robot, info: SettingsFieldInfo) : SettingField<Int>(robot, info) {
    init {
        require(info.type != FieldType.F32 && info.type != FieldType.CHAR && info.type != FieldType.U32 && info.count == 1) {
            "${info.path} is not an integer"
        }
    }

    override fun decode(settings: ByteArray): Int = readNumber(settings, info.offset, info.type).toInt()
    override fun encode(value: Int, out: ByteArray) = writeNumber(out, 0, info.type, value, path)
}

/** A settings field holding a fixed number of integers (e.g. a calibration value per line sensor spot). */
public class IntListSetting internal constructor(robot: Robot, info: SettingsFieldInfo) : SettingField<List<Int>>(robot, info) {
    init {
        require(info.type != FieldType.F32 && info.type != FieldType.CHAR && info.count > 1) { "${info.path} is not an integer array" }
    }

    /** Number of elements. */
    public val count: Int get() = info.count

    override fun decode(settings: ByteArray): List<Int> =
        List(info.count) { readNumber(settings, info.offset + it * info.type.size, info.type).toInt() }

    override fun encode(value: List<Int>, out: ByteArray) {
        require(value.size == info.count) { "$path holds ${info.count} values, not ${value.size}" }
        value.forEachIndexed { i, v -> writeNumber(out, i * info.type.size, info.type, v, path) }
    }
}

/** A settings field holding text (UTF-8, NUL-padded to its size). */
public class TextSetting internal constructor(robot: Robot, info: SettingsFieldInfo) : SettingField<String>(robot, info) {
    init {
        require(info.type == FieldType.CHAR) { "${info.path} is not text" }
    }

    /** Largest length in UTF-8 bytes. */
    public val maxBytes: Int get() = info.count

    override fun decode(settings: ByteArray): String {
        var end = info.offset
        while (end < info.offset + info.count && settings[end] != 0.toByte()) end++
        return settings.decodeToString(info.offset, end)
    }

    override fun encode(value: String, out: ByteArray) {
        val raw = value.encodeToByteArray()
        require(raw.size <= info.count) { "\"$value\" is longer than the $path field (${info.count} bytes)" }
        raw.copyInto(out)
    }
}

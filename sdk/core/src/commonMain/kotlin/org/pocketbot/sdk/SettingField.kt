package org.pocketbot.sdk

import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.distinctUntilChanged
import kotlinx.coroutines.flow.map
import org.pocketbot.protocol.FieldType
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.SettingsFieldInfo
import org.pocketbot.protocol.UpdateSettings
import org.pocketbot.sdk.internal.SettingsMirror
import org.pocketbot.sdk.internal.link.LinkPort
import org.pocketbot.sdk.internal.readNumber
import org.pocketbot.sdk.internal.writeNumber

/**
 * One leaf of the robot's settings struct (thesis 9.6), e.g. `robot.settings.linePid.kp`.
 *
 * Every setting has one [name], its path in the protocol definition (`line_pid.kp`): `robot.settings["line_pid.kp"]`,
 * the JSON export (`{"line_pid": {"kp": ...}}`, grouped by the part before the dot), the command line and the docs
 * all use it; the Kotlin tree spells the same two parts in camelCase (`robot.settings.linePid.kp`).
 *
 * [value] is the value the robot confirmed last. [set] sends only this field (`update_settings` with its offset and
 * bytes), suspends until the robot acknowledged it, retransmits on timeout, and throws [SettingRefusedException] when
 * the robot refuses it (the robot is the referee of [min]..[max]).
 */
public sealed class SettingField<T> constructor(
    private val link: LinkPort,
    private val mirror: SettingsMirror,
    path: String,
) {
    // Looked up by name, not passed in: a sealed class's constructor shows in the API, and it names no wire type.
    internal val info: SettingsFieldInfo = SETTINGS_FIELDS.firstOrNull { it.path == path } ?: error("the protocol has no setting $path")

    /** The setting's one name, e.g. `line_pid.kp`. */
    public val name: String get() = info.path

    /** Unit of the value (`m/s`, `ms`, ...), empty when it has none. */
    public val unit: String get() = info.unit

    /** Lowest value the robot accepts, null when unbounded. */
    public val min: Double? get() = info.min

    /** Highest value the robot accepts, null when unbounded. */
    public val max: Double? get() = info.max

    /** What the setting does, from the protocol definition. */
    public val doc: String get() = info.doc

    /** The value the robot confirmed last (read at connect, then every acknowledged write). */
    public val value: T get() = decode(mirror.bytes.value)

    /**
     * [value] as people read and type it: a real number as the shortest decimal that reads back to the robot's float
     * (`0.0004`), an enumeration by name (`full`), a list as `[1, 2, 3]`, text as it is. [parse] reads it back.
     */
    public val valueText: String get() = format(value)

    /**
     * What the robot accepts, for people: `0..100000` for a number with bounds (as [valueText] writes numbers), the
     * names for an enumeration (`none, full, reduced`), empty otherwise.
     */
    public open val rangeText: String
        get() {
            val lo = min ?: return ""
            val hi = max ?: return ""
            return "${lo.toDecimalString()}..${hi.toDecimalString()}"
        }

    /** [value] now and after every change. */
    public val changes: Flow<T> get() = mirror.bytes.map { decode(it) }.distinctUntilChanged()

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
            link.command(UpdateSettings(info.offset, bytes))
        } catch (e: NotDriverException) {
            throw e // not the value: the robot takes no settings from a host that watches
        } catch (e: CommandRefusedException) {
            throw SettingRefusedException(name, value, e.code, e.detail, format(value), rangeText)
        }
        link.serial { mirror.written(info.offset, bytes) }
    }

    /** Parses [text] as a value of this setting (as a person types it), for [set]. */
    public abstract fun parse(text: String): T

    /** [value] as people read it, and as [parse] reads it back (see [valueText]). */
    public open fun format(value: T): String = value.toString()

    internal abstract fun decode(settings: ByteArray): T

    /** This field's value in [settings], formatted. */
    internal fun textOf(settings: ByteArray): String = format(decode(settings))
    internal abstract fun encode(value: T, out: ByteArray)

    override fun toString(): String = "$name = $valueText${if (unit.isEmpty()) "" else " $unit"}"
}

/** A setting holding a real number (stored by the robot as binary32, so it reads back rounded to that). */
public class DoubleSetting internal constructor(link: LinkPort, mirror: SettingsMirror, path: String) :
    SettingField<Double>(link, mirror, path) {
    init {
        require(info.type == FieldType.F32 && info.count == 1) { "${info.path} is not a real number" }
    }

    override fun parse(text: String): Double = text.trim().toDoubleOrNull() ?: throw IllegalArgumentException("$name needs a number, not \"$text\"")
    override fun format(value: Double): String = value.toFloat().toDecimalString()
    override fun decode(settings: ByteArray): Double = readNumber(settings, info.offset, info.type).toDouble()
    override fun encode(value: Double, out: ByteArray): Unit = writeNumber(out, 0, info.type, value, name)
}

/** A setting holding an integer (u8, i8, u16, i16, i32). */
public class IntSetting internal constructor(link: LinkPort, mirror: SettingsMirror, path: String) :
    SettingField<Int>(link, mirror, path) {
    init {
        require(info.type != FieldType.F32 && info.type != FieldType.CHAR && info.type != FieldType.U32 && info.count == 1) {
            "${info.path} is not an integer"
        }
    }

    override fun parse(text: String): Int = text.trim().toIntOrNull() ?: throw IllegalArgumentException("$name needs an integer, not \"$text\"")
    override fun decode(settings: ByteArray): Int = readNumber(settings, info.offset, info.type).toInt()
    override fun encode(value: Int, out: ByteArray): Unit = writeNumber(out, 0, info.type, value, name)
}

/** A setting holding one of the named values of an enumeration of the protocol (e.g. the sync mode). */
public class EnumSetting<E : Enum<E>> internal constructor(
    link: LinkPort,
    mirror: SettingsMirror,
    path: String,
    /** Every value the setting can hold. */
    public val values: List<E>,
    private val codeOf: (E) -> Int,
) : SettingField<E>(link, mirror, path) {
    init {
        require(info.type == FieldType.U8 && info.count == 1) { "${info.path} is not an enumeration" }
    }

    /** The names of [values] as people read and type them: `none`, `full`, `reduced`. */
    public val names: List<String> get() = values.map { it.name.lowercase() }

    override val rangeText: String get() = names.joinToString()

    override fun parse(text: String): E = valueNamed(text)
        ?: throw IllegalArgumentException("$name is one of ${names.joinToString()}, not \"$text\"")

    override fun format(value: E): String = value.name.lowercase()

    /** The name of the value with wire [code], or null when none of [values] has it. */
    internal fun nameOf(code: Int): String? = valueWithCode(code)?.let(::format)

    /** The wire code of the value called [name] (as [parse] reads it), or null. */
    internal fun codeOfName(name: String): Int? = valueNamed(name)?.let(codeOf)

    private fun valueNamed(text: String): E? = values.firstOrNull { it.name.equals(text.trim(), ignoreCase = true) }

    private fun valueWithCode(code: Int): E? = values.firstOrNull { codeOf(it) == code }

    override fun decode(settings: ByteArray): E = valueWithCode(readNumber(settings, info.offset, info.type).toInt()) ?: values.first()

    override fun encode(value: E, out: ByteArray): Unit = writeNumber(out, 0, info.type, codeOf(value), name)
}

/** A setting holding a fixed number of integers (e.g. a calibration value per line sensor spot). */
public class IntListSetting internal constructor(link: LinkPort, mirror: SettingsMirror, path: String) :
    SettingField<List<Int>>(link, mirror, path) {
    init {
        require(info.type != FieldType.F32 && info.type != FieldType.CHAR && info.count > 1) { "${info.path} is not an integer array" }
    }

    /** Number of elements. */
    public val count: Int get() = info.count

    /** Parses `[1, 2, 3]` or `1,2,3`. */
    override fun parse(text: String): List<Int> {
        val parts = text.trim().removePrefix("[").removeSuffix("]").split(',').map { it.trim() }.filter { it.isNotEmpty() }
        require(parts.size == count) { "$name holds $count values, not ${parts.size}" }
        return parts.map { it.toIntOrNull() ?: throw IllegalArgumentException("$name needs integers, not \"$it\"") }
    }

    override fun decode(settings: ByteArray): List<Int> =
        List(info.count) { readNumber(settings, info.offset + it * info.type.size, info.type).toInt() }

    override fun encode(value: List<Int>, out: ByteArray) {
        require(value.size == info.count) { "$name holds ${info.count} values, not ${value.size}" }
        value.forEachIndexed { i, v -> writeNumber(out, i * info.type.size, info.type, v, name) }
    }
}

/** A setting holding text (UTF-8, NUL-padded to its size). */
public class TextSetting internal constructor(link: LinkPort, mirror: SettingsMirror, path: String) :
    SettingField<String>(link, mirror, path) {
    init {
        require(info.type == FieldType.CHAR) { "${info.path} is not text" }
    }

    /** Largest length in UTF-8 bytes. */
    public val maxBytes: Int get() = info.count

    override fun parse(text: String): String = text

    override fun decode(settings: ByteArray): String {
        var end = info.offset
        while (end < info.offset + info.count && settings[end] != 0.toByte()) end++
        return settings.decodeToString(info.offset, end)
    }

    override fun encode(value: String, out: ByteArray) {
        val raw = value.encodeToByteArray()
        require(raw.size <= info.count) { "\"$value\" is longer than the $name field (${info.count} bytes)" }
        raw.copyInto(out)
    }
}

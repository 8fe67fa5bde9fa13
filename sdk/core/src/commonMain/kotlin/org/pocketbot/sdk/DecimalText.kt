package org.pocketbot.sdk

import kotlin.math.abs
import kotlin.math.floor
import kotlin.math.log10
import kotlin.math.pow

/**
 * This binary32 value as people read it: the shortest decimal that reads back to the same float, in plain notation,
 * `0.0004` (not `4.0E-4`, nor `3.9999998989515E-4` as the float's exact value reads), `0.15` (not
 * `0.15000000596046448`), `2` (not `2.0`). The robot stores its real-number settings as such floats: every face shows
 * them this way, and JSON files write the same digits as a number, so they read back to the same float.
 *
 * ```
 * 0.0004f.toDecimalString()                       // "0.0004"
 * robot.settings.linePid.kp.valueText              // the same, for a setting
 * ```
 */
public fun Float.toDecimalString(): String {
    if (isNaN() || isInfinite()) return toString()
    if (this == 0f) return "0"
    val sign = if (this < 0) "-" else ""
    val v = abs(toDouble())
    var e = floor(log10(v)).toInt()
    for (digits in 1..9) {
        // The decimals of this many digits nearest to the value: one of them reads back to it if any does.
        val shift = digits - 1 - e
        val scaled = v * 10.0.pow(shift)
        val nearest = (floor(scaled).toLong() - 1..floor(scaled).toLong() + 2)
            .filter { it > 0 && readsBack(decimal(it, shift), this) }
            .minByOrNull { abs(it - scaled) }
        if (nearest != null) return sign + decimal(nearest, shift)
        if (digits == 1 && floor(scaled) >= 10) e++ // log10 rounded up across a power of ten
    }
    return toString() // not reached: 9 significant digits always read back
}

/**
 * This value as people read it, in plain notation (no exponent): the digits the platform chose to read back to it,
 * `100000` for `1.0E5`, `0.00025` for `2.5E-4`. For a value the robot holds as a float, use [Float.toDecimalString].
 */
public fun Double.toDecimalString(): String {
    if (isNaN() || isInfinite()) return toString()
    val text = toString().lowercase()
    val sign = if (text.startsWith('-')) "-" else ""
    val mantissa = text.removePrefix("-").substringBefore('e')
    val exponent = text.substringAfter('e', "0").removePrefix("+").toInt()
    val dot = mantissa.indexOf('.').let { if (it < 0) mantissa.length else it }
    val plain = plain(mantissa.replace(".", ""), dot + exponent)
    return if (plain == "0") plain else sign + plain
}

/** The integer [n] divided by 10^[shift], in plain notation. */
private fun decimal(n: Long, shift: Int): String = n.toString().let { plain(it, it.length - shift) }

/**
 * [digits] with the decimal point [point] digits from their start (at or before the start: zeros come first), without
 * trailing zeros after the point.
 */
private fun plain(digits: String, point: Int): String {
    val text = when {
        point <= 0 -> "0." + "0".repeat(-point) + digits
        point >= digits.length -> digits + "0".repeat(point - digits.length)
        else -> digits.substring(0, point) + "." + digits.substring(point)
    }
    val trimmed = if ('.' in text) text.trimEnd('0').trimEnd('.') else text
    return trimmed.trimStart('0').let { if (it.isEmpty() || it.startsWith('.')) "0$it" else it }
}

/** True when [text] reads back (as people's text is read: to a double, then to the robot's float) to [value]'s size. */
private fun readsBack(text: String, value: Float): Boolean =
    text.toDouble().toFloat().toBits() == abs(value).toBits()

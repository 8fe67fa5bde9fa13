@file:Suppress("NOTHING_TO_INLINE")

package org.pocketbot.protocol

// Little-endian access at absolute offsets, for the generated codecs. A codec checks the length once per packet
// (Frames.decode against PACKET_SPECS, or the caller), then reads and writes every field at its fixed offset:
// no cursor, no per-field length check, no intermediate buffer.

internal inline fun ByteArray.u8(i: Int): Int = this[i].toInt() and 0xFF
internal inline fun ByteArray.i8(i: Int): Int = this[i].toInt()
internal inline fun ByteArray.u16(i: Int): Int = (this[i].toInt() and 0xFF) or ((this[i + 1].toInt() and 0xFF) shl 8)
internal inline fun ByteArray.i16(i: Int): Int = (this[i].toInt() and 0xFF) or (this[i + 1].toInt() shl 8)
internal inline fun ByteArray.i32(i: Int): Int =
    (this[i].toInt() and 0xFF) or ((this[i + 1].toInt() and 0xFF) shl 8) or
        ((this[i + 2].toInt() and 0xFF) shl 16) or (this[i + 3].toInt() shl 24)
internal inline fun ByteArray.u32(i: Int): Long = i32(i).toLong() and 0xFFFF_FFFFL
internal inline fun ByteArray.f32(i: Int): Float = Float.fromBits(i32(i))

/** A NUL-padded UTF-8 text field of [n] bytes at [i]. */
internal fun ByteArray.text(i: Int, n: Int): String {
    var len = 0
    while (len < n && this[i + len] != 0.toByte()) len++
    return decodeToString(i, i + len)
}

internal inline fun ByteArray.putU8(i: Int, v: Int) { this[i] = v.toByte() }
internal inline fun ByteArray.putI8(i: Int, v: Int) { this[i] = v.toByte() }
internal inline fun ByteArray.putU16(i: Int, v: Int) { this[i] = v.toByte(); this[i + 1] = (v shr 8).toByte() }
internal inline fun ByteArray.putI16(i: Int, v: Int) = putU16(i, v)
internal inline fun ByteArray.putI32(i: Int, v: Int) {
    this[i] = v.toByte(); this[i + 1] = (v shr 8).toByte(); this[i + 2] = (v shr 16).toByte(); this[i + 3] = (v shr 24).toByte()
}
internal inline fun ByteArray.putU32(i: Int, v: Long) = putI32(i, v.toInt())
internal inline fun ByteArray.putF32(i: Int, v: Float) = putI32(i, v.toRawBits())

/** A NUL-padded UTF-8 text field of [n] bytes at [i]; text longer than [n] bytes is refused. */
internal fun ByteArray.putText(i: Int, text: String, n: Int) {
    val raw = text.encodeToByteArray()
    require(raw.size <= n) { "text \"$text\" is longer than $n bytes" }
    raw.copyInto(this, i)
    fill(0, i + raw.size, i + n)
}

/**
 * An immutable `List<Int>` over an [IntArray]: what the codecs decode numeric arrays into, so decoding boxes
 * nothing. Equality and hash code are those of any [List] (equal to `listOf(...)` with the same elements).
 */
internal class IntArrayList(internal val array: IntArray) : AbstractList<Int>(), RandomAccess {
    override val size: Int get() = array.size
    override fun get(index: Int): Int = array[index]
    override fun contains(element: Int): Boolean = array.contains(element)
    override fun indexOf(element: Int): Int = array.indexOf(element)
    override fun lastIndexOf(element: Int): Int = array.lastIndexOf(element)
    override fun hashCode(): Int {
        var h = 1
        for (v in array) h = 31 * h + v
        return h
    }
    override fun equals(other: Any?): Boolean = when (other) {
        is IntArrayList -> array.contentEquals(other.array)
        else -> super.equals(other)
    }
}

/** The elements of a numeric array field, checked for their count: no copy when [list] came from a decoder. */
internal fun intsOf(list: List<Int>, count: Int, name: String): IntArray {
    require(list.size == count) { "$name needs $count values" }
    return if (list is IntArrayList) list.array else IntArray(count) { list[it] }
}

/** A count in a payload disagrees with the bytes that are there. */
internal class LengthMismatch(val expected: Int, val actual: Int) : RuntimeException("expected $expected bytes, found $actual")

internal fun ByteArray.toHex(): String = joinToString("") { (it.toInt() and 0xFF).toString(16).padStart(2, '0') }

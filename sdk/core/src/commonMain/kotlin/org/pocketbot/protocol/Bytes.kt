package org.pocketbot.protocol

/** Reads little-endian values from [bytes] between [start] and [end]; the generated codecs use it. */
internal class ByteReader(private val bytes: ByteArray, start: Int = 0, private val end: Int = bytes.size) {
    private var pos = start

    val remaining: Int get() = end - pos

    private fun take(n: Int): Int {
        if (n > remaining) throw LengthMismatch(n, remaining)
        return pos.also { pos += n }
    }

    private fun u8At(i: Int): Int = bytes[i].toInt() and 0xFF

    fun readU8(): Int = u8At(take(1))
    fun readI8(): Int = bytes[take(1)].toInt()
    fun readU16(): Int = take(2).let { u8At(it) or (u8At(it + 1) shl 8) }
    fun readI16(): Int = readU16().toShort().toInt()
    fun readI32(): Int = take(4).let { u8At(it) or (u8At(it + 1) shl 8) or (u8At(it + 2) shl 16) or (u8At(it + 3) shl 24) }
    fun readU32(): Long = readI32().toLong() and 0xFFFF_FFFFL
    fun readF32(): Float = Float.fromBits(readI32())
    fun readBytes(n: Int): ByteArray = take(n).let { bytes.copyOfRange(it, it + n) }

    /** A NUL-padded UTF-8 text field of [n] bytes. */
    fun readText(n: Int): String {
        val at = take(n)
        var len = 0
        while (len < n && bytes[at + len] != 0.toByte()) len++
        return bytes.decodeToString(at, at + len)
    }
}

/** Writes little-endian values into a growing buffer; the generated codecs use it. */
internal class ByteWriter(capacity: Int = 32) {
    private var buf = ByteArray(capacity)
    var size: Int = 0
        private set

    private fun room(n: Int): Int {
        if (size + n > buf.size) buf = buf.copyOf(maxOf(buf.size * 2, size + n))
        return size.also { size += n }
    }

    fun writeU8(v: Int) { buf[room(1)] = v.toByte() }
    fun writeI8(v: Int) = writeU8(v)
    fun writeU16(v: Int) { val at = room(2); buf[at] = v.toByte(); buf[at + 1] = (v shr 8).toByte() }
    fun writeI16(v: Int) = writeU16(v)
    fun writeI32(v: Int) {
        val at = room(4)
        for (i in 0 until 4) buf[at + i] = (v shr (8 * i)).toByte()
    }
    fun writeU32(v: Long) = writeI32(v.toInt())
    fun writeF32(v: Float) = writeI32(v.toRawBits())
    fun writeBytes(b: ByteArray) { b.copyInto(buf, room(b.size)) }

    /** A NUL-padded UTF-8 text field of [n] bytes; text longer than [n] bytes is refused. */
    fun writeText(text: String, n: Int) {
        val raw = text.encodeToByteArray()
        require(raw.size <= n) { "text \"$text\" is longer than $n bytes" }
        writeBytes(raw)
        room(n - raw.size) // the buffer is zeroed where it was never written
        buf.fill(0, size - (n - raw.size), size)
    }

    fun toByteArray(): ByteArray = buf.copyOf(size)
}

/** A count in a payload disagrees with the bytes that are there. */
internal class LengthMismatch(val expected: Int, val actual: Int) : RuntimeException("expected $expected bytes, found $actual")

internal fun ByteArray.toHex(): String = joinToString("") { (it.toInt() and 0xFF).toString(16).padStart(2, '0') }

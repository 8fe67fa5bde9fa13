package org.pocketbot.protocol

/**
 * CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor), as the firmware computes it.
 * Slicing-by-8: eight bytes per step through eight 256-entry tables (table k is one byte followed by k zero
 * bytes), so the loop-carried dependency is one step per 8 bytes instead of one per byte.
 */
public object Crc16 {
    private val t0 = IntArray(256) { n ->
        var crc = n shl 8
        repeat(8) { crc = if (crc and 0x8000 != 0) (crc shl 1) xor 0x1021 else crc shl 1 }
        crc and 0xFFFF
    }
    private fun next(prev: IntArray) = IntArray(256) { n -> ((prev[n] shl 8) xor t0[prev[n] ushr 8]) and 0xFFFF }
    private val t1 = next(t0)
    private val t2 = next(t1)
    private val t3 = next(t2)
    private val t4 = next(t3)
    private val t5 = next(t4)
    private val t6 = next(t5)
    private val t7 = next(t6)

    /** The CRC of [length] bytes of [bytes] from [offset]. */
    public fun compute(bytes: ByteArray, offset: Int = 0, length: Int = bytes.size - offset): Int {
        var crc = 0xFFFF
        var i = offset
        val end = offset + length
        val t0 = t0; val t1 = t1; val t2 = t2; val t3 = t3; val t4 = t4; val t5 = t5; val t6 = t6; val t7 = t7
        while (i <= end - 8) {
            crc = t7[(crc ushr 8) xor (bytes[i].toInt() and 0xFF)] xor
                t6[(crc and 0xFF) xor (bytes[i + 1].toInt() and 0xFF)] xor
                t5[bytes[i + 2].toInt() and 0xFF] xor t4[bytes[i + 3].toInt() and 0xFF] xor
                t3[bytes[i + 4].toInt() and 0xFF] xor t2[bytes[i + 5].toInt() and 0xFF] xor
                t1[bytes[i + 6].toInt() and 0xFF] xor t0[bytes[i + 7].toInt() and 0xFF]
            i += 8
        }
        while (i < end) {
            crc = ((crc shl 8) xor t0[((crc ushr 8) xor bytes[i].toInt()) and 0xFF]) and 0xFFFF
            i++
        }
        return crc
    }
}

package org.pocketbot.protocol

/** CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor), as the firmware computes it. */
public object Crc16 {
    private val table = IntArray(256) { n ->
        var crc = n shl 8
        repeat(8) { crc = if (crc and 0x8000 != 0) (crc shl 1) xor 0x1021 else crc shl 1 }
        crc and 0xFFFF
    }

    /** The CRC of [length] bytes of [bytes] from [offset]. */
    public fun compute(bytes: ByteArray, offset: Int = 0, length: Int = bytes.size - offset): Int {
        var crc = 0xFFFF
        for (i in offset until offset + length) {
            crc = ((crc shl 8) xor table[((crc shr 8) xor bytes[i].toInt()) and 0xFF]) and 0xFFFF
        }
        return crc
    }
}

package org.pocketbot.sdk.internal

import org.pocketbot.protocol.FieldType
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.SETTINGS_DEFAULTS
import org.pocketbot.protocol.Settings
import org.pocketbot.protocol.SettingsFieldInfo

internal fun Settings.toBytes(): ByteArray = ByteArray(ProtocolInfo.SETTINGS_SIZE).also { encodeTo(it, 0) }

internal fun settingsOf(bytes: ByteArray): Settings {
    require(bytes.size >= ProtocolInfo.SETTINGS_SIZE) { "settings need ${ProtocolInfo.SETTINGS_SIZE} bytes, not ${bytes.size}" }
    return Settings.decode(bytes, 0)
}

internal val DEFAULT_SETTINGS_BYTES: ByteArray = SETTINGS_DEFAULTS.toBytes()

/** Reads one numeric element of a field from settings bytes (little-endian). */
internal fun readNumber(bytes: ByteArray, at: Int, type: FieldType): Number {
    fun u(i: Int) = bytes[at + i].toInt() and 0xFF
    return when (type) {
        FieldType.U8, FieldType.CHAR -> u(0)
        FieldType.I8 -> bytes[at].toInt()
        FieldType.U16 -> u(0) or (u(1) shl 8)
        FieldType.I16 -> (u(0) or (u(1) shl 8)).toShort().toInt()
        FieldType.I32 -> u(0) or (u(1) shl 8) or (u(2) shl 16) or (u(3) shl 24)
        FieldType.U32 -> (u(0) or (u(1) shl 8) or (u(2) shl 16) or (u(3) shl 24)).toLong() and 0xFFFF_FFFFL
        FieldType.F32 -> Float.fromBits(u(0) or (u(1) shl 8) or (u(2) shl 16) or (u(3) shl 24))
    }
}

/** Writes one numeric element; throws [IllegalArgumentException] when it does not fit the wire type at all. */
internal fun writeNumber(out: ByteArray, at: Int, type: FieldType, value: Number, path: String) {
    fun put(v: Long, n: Int) { for (i in 0 until n) out[at + i] = (v shr (8 * i)).toByte() }
    fun ranged(lo: Long, hi: Long): Long {
        val v = value.toLong()
        require(value.toDouble() == v.toDouble() && v in lo..hi) { "$value does not fit $path ($type, $lo..$hi)" }
        return v
    }
    when (type) {
        FieldType.U8, FieldType.CHAR -> put(ranged(0, 255), 1)
        FieldType.I8 -> put(ranged(-128, 127), 1)
        FieldType.U16 -> put(ranged(0, 65535), 2)
        FieldType.I16 -> put(ranged(-32768, 32767), 2)
        FieldType.U32 -> put(ranged(0, 0xFFFF_FFFFL), 4)
        FieldType.I32 -> put(ranged(Int.MIN_VALUE.toLong(), Int.MAX_VALUE.toLong()), 4)
        FieldType.F32 -> put(value.toFloat().toRawBits().toLong(), 4)
    }
}

internal fun SettingsFieldInfo.slice(bytes: ByteArray): ByteArray = bytes.copyOfRange(offset, offset + size)

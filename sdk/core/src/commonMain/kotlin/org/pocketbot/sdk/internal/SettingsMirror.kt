package org.pocketbot.sdk.internal

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.Crc16
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.Packet
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.Settings
import org.pocketbot.protocol.SettingsData
import org.pocketbot.sdk.DebugLog
import org.pocketbot.sdk.RobotException
import org.pocketbot.sdk.SettingsCache
import org.pocketbot.sdk.SettingsCacheKey
import org.pocketbot.sdk.SettingsSnapshot
import org.pocketbot.sdk.internal.link.LinkPort

/**
 * The host's copy of the robot's settings struct: only bytes the robot confirmed (read, or acknowledged after a
 * write). Touched only on the link's serial context; [bytes] and [values] may be read from anywhere.
 */
internal class SettingsMirror(private val link: LinkPort, private val cache: SettingsCache?, private val debugLog: DebugLog) {
    private val _bytes = MutableStateFlow(DEFAULT_SETTINGS_BYTES.copyOf())
    private val _values = MutableStateFlow(settingsOf(DEFAULT_SETTINGS_BYTES))

    /** The confirmed bytes; a new array on every change, never modified in place. */
    val bytes: StateFlow<ByteArray> = _bytes.asStateFlow()

    /** The confirmed settings, decoded (for the SDK's own hot paths, such as odometry on every state update). */
    val values: StateFlow<Settings> = _values.asStateFlow()

    private val _snapshot = MutableStateFlow(SettingsSnapshot(_bytes.value))

    /** The confirmed settings, for users. */
    val snapshot: StateFlow<SettingsSnapshot> = _snapshot.asStateFlow()

    /**
     * Called with the offset and bytes of every change the user made and the robot confirmed (a write, a read of
     * them all, the defaults); not for the reads the SDK does itself when it reconnects.
     */
    var onUserChange: ((offset: Int, data: ByteArray) -> Unit)? = null

    private var cacheKey: SettingsCacheKey? = null

    /**
     * Makes the mirror match the robot that sent [hello]: from the cache when an entry there has the robot's settings
     * checksum, else unchanged when the mirror already has it, else read with `read_settings` through [exchange].
     */
    suspend fun align(hello: Hello, address: String, exchange: suspend (Packet) -> Unit) {
        val key = SettingsCacheKey(address, hello.layoutHash)
        cacheKey = key
        if (crcOf(_bytes.value) == hello.settingsCrc) return
        val cached = cache?.get(key)
        if (cached != null && cached.size == ProtocolInfo.SETTINGS_SIZE && crcOf(cached) == hello.settingsCrc) {
            replace(cached)
            debugLog.host(2, "settings of ${hello.name} at $address taken from the cache")
            return
        }
        read(exchange)
    }

    /** Reads the whole struct with `read_settings` through [exchange], again until every byte arrived. */
    suspend fun read(exchange: suspend (Packet) -> Unit): ByteArray {
        repeat(READ_ATTEMPTS) {
            val buffer = ByteArray(ProtocolInfo.SETTINGS_SIZE)
            val coverage = BooleanArray(ProtocolInfo.SETTINGS_SIZE)
            link.settingsSink = { chunk -> collect(chunk, buffer, coverage) }
            try {
                exchange(ReadSettings)
            } finally {
                link.settingsSink = null
            }
            if (coverage.all { it }) {
                replace(buffer)
                return buffer
            }
            debugLog.host(1, "settings read incomplete (${coverage.count { !it }} bytes missing), reading again")
        }
        throw RobotException("settings could not be read completely")
    }

    private fun collect(chunk: SettingsData, buffer: ByteArray, coverage: BooleanArray): Boolean {
        if (chunk.offset + chunk.data.size > buffer.size) return false
        chunk.data.copyInto(buffer, chunk.offset)
        coverage.fill(true, chunk.offset, chunk.offset + chunk.data.size)
        return true
    }

    /** The robot acknowledged [data] at [offset]. */
    suspend fun written(offset: Int, data: ByteArray) {
        val copy = _bytes.value.copyOf()
        data.copyInto(copy, offset)
        replace(copy)
        onUserChange?.invoke(offset, data)
    }

    /** The robot holds [data] at [offset] because of a command that is not a settings write (set_sync). */
    suspend fun confirmed(offset: Int, data: ByteArray) {
        val now = _bytes.value
        if ((data.indices).all { now[offset + it] == data[it] }) return
        val copy = now.copyOf()
        data.copyInto(copy, offset)
        replace(copy)
    }

    /** The user read the whole struct (or loaded the defaults): everything in it may have changed. */
    fun changedByUser() {
        val all = _bytes.value
        onUserChange?.invoke(0, all)
    }

    private suspend fun replace(bytes: ByteArray) {
        val copy = bytes.copyOf()
        _bytes.value = copy
        _values.value = settingsOf(copy)
        _snapshot.value = SettingsSnapshot(copy)
        cacheKey?.let { cache?.put(it, copy) }
    }

    private companion object {
        const val READ_ATTEMPTS = 3

        fun crcOf(bytes: ByteArray): Int = Crc16.compute(bytes, 0, bytes.size)
    }
}

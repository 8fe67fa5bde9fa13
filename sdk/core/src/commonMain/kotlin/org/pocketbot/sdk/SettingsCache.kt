package org.pocketbot.sdk

import kotlinx.coroutines.sync.Mutex
import kotlinx.coroutines.sync.withLock

/**
 * Identifies cached settings: the robot at [address] under one settings layout. Robot ids are no key: every robot
 * starts with id 1.
 */
public class SettingsCacheKey(public val address: String, public val layoutHash: Long) {
    override fun equals(other: Any?): Boolean = other is SettingsCacheKey && address == other.address && layoutHash == other.layoutHash
    override fun hashCode(): Int = address.hashCode() * 31 + layoutHash.hashCode()
    override fun toString(): String = "$address (layout 0x${layoutHash.toString(16).uppercase()})"
}

/**
 * Keeps the settings bytes learned from robots, so that connecting again to a known robot skips `read_settings`
 * (which takes a few hundred milliseconds per robot on a slow link). The SDK uses an entry only when the robot's
 * `hello` reports the same settings checksum, so an entry can be stale without harm. Implementations must be safe
 * to call from any coroutine.
 */
public interface SettingsCache {
    /** The cached settings bytes of [key], or null. */
    public suspend fun get(key: SettingsCacheKey): ByteArray?

    /** Remembers [settings] (the whole struct) for [key]. */
    public suspend fun put(key: SettingsCacheKey, settings: ByteArray)

    public companion object {
        /** The process-wide in-memory cache [RobotOptions] uses by default. */
        public val shared: SettingsCache = InMemorySettingsCache()
    }
}

/** A [SettingsCache] in memory, lost when the process ends. */
public class InMemorySettingsCache : SettingsCache {
    private val mutex = Mutex()
    private val entries = HashMap<SettingsCacheKey, ByteArray>()

    override suspend fun get(key: SettingsCacheKey): ByteArray? = mutex.withLock { entries[key]?.copyOf() }

    override suspend fun put(key: SettingsCacheKey, settings: ByteArray) {
        mutex.withLock { entries[key] = settings.copyOf() }
    }
}

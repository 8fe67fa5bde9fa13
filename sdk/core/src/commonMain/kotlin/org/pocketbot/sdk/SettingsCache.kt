package org.pocketbot.sdk

import kotlinx.coroutines.sync.Mutex
import kotlinx.coroutines.sync.withLock

/** Identifies cached settings: a robot id under one settings layout. */
public data class SettingsCacheKey(public val robotId: Int, public val layoutHash: Long)

/**
 * Keeps the settings bytes learned from robots, so that connecting again to a known robot skips `read_settings`
 * (which takes a few hundred milliseconds per robot on a slow link). Implementations must be safe to call from any
 * coroutine.
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

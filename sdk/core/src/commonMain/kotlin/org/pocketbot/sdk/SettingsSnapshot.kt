package org.pocketbot.sdk

/**
 * All of a robot's settings at one moment, as the robot confirmed them: `snapshot[robot.settings.linePid.kp]` reads
 * one value in the setting's own type (numbers as [Double], enums as enums). Snapshots are immutable; two are equal
 * when they hold the same values.
 */
public class SettingsSnapshot internal constructor(private val bytes: ByteArray) {
    /** The value of [field] in this snapshot. */
    public operator fun <T> get(field: SettingField<T>): T = field.decode(bytes)

    override fun equals(other: Any?): Boolean = other is SettingsSnapshot && bytes.contentEquals(other.bytes)

    override fun hashCode(): Int = bytes.contentHashCode()

    override fun toString(): String = "SettingsSnapshot(${bytes.size} bytes)"
}

package org.pocketbot.sdk

import kotlinx.coroutines.flow.StateFlow
import org.pocketbot.protocol.LoadDefaults
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.SaveSettings
import org.pocketbot.protocol.UpdateSettings
import org.pocketbot.sdk.internal.SettingsJson
import org.pocketbot.sdk.internal.SettingsMirror
import org.pocketbot.sdk.internal.link.LinkPort

/**
 * What every settings tree can do: find a setting by name, read them all, save, load defaults, export and import
 * JSON. [RobotSettings] adds the typed tree, generated from the protocol definition.
 */
public abstract class SettingsBase internal constructor(internal val linkPort: LinkPort, internal val store: SettingsMirror) {
    private val byName = LinkedHashMap<String, SettingField<*>>()

    internal fun <F : SettingField<*>> register(f: F): F = f.also { byName[it.name] = it }


    internal fun double(name: String): DoubleSetting = register(DoubleSetting(linkPort, store, name))
    internal fun int(name: String): IntSetting = register(IntSetting(linkPort, store, name))
    internal fun ints(name: String): IntListSetting = register(IntListSetting(linkPort, store, name))
    internal fun text(name: String): TextSetting = register(TextSetting(linkPort, store, name))
    internal fun <E : Enum<E>> enum(name: String, values: List<E>, codeOf: (E) -> Int): EnumSetting<E> =
        register(EnumSetting(linkPort, store, name, values, codeOf))

    /** Every setting, in struct order. */
    public val fields: List<SettingField<*>> get() = byName.values.sortedBy { it.info.offset }

    private val json by lazy { SettingsJson(byName.values.filterIsInstance<EnumSetting<*>>().associateBy { it.name }) }

    /** The setting called [name] (e.g. `line_pid.kp`), or null. */
    public operator fun get(name: String): SettingField<*>? = byName[name]

    /** All settings as the robot confirmed them, a new snapshot on every acknowledged change. */
    public val values: StateFlow<SettingsSnapshot> get() = store.snapshot

    /** Reads the whole settings struct from the robot again (`read_settings`), updating every setting. */
    public suspend fun readAll(): SettingsSnapshot {
        linkPort.serial { store.read { linkPort.command(it) } }
        store.changedByUser()
        return values.value
    }

    /** Saves the robot's current settings to its EEPROM, so they survive a reset. */
    public suspend fun save() {
        linkPort.command(SaveSettings)
    }

    /**
     * Replaces the robot's settings with its compiled-in defaults (not saved until [save]) and reads them back.
     * That includes the sync mode: [Robot.reflector] follows.
     */
    public suspend fun loadDefaults() {
        linkPort.command(LoadDefaults)
        readAll()
    }

    /**
     * All settings as JSON, grouped by the first part of their names:
     * `{"identity": {"robot_id": 1, "name": "PocketBot"}, "sync": {"mode": "full", ...}, "speed_pid": {"kp": 2500, ...}, ...}`.
     * A real number is the shortest decimal that reads back to the robot's float (`0.0004`), an enumeration its name.
     */
    public fun exportJson(): String = json.export(store.bytes.value)

    /**
     * Writes every setting in [json] (the format of [exportJson]; settings may be left out, an enumeration may be given
     * by its code too) whose value differs from
     * the robot's, adjacent settings together in one `update_settings` of at most 64 bytes. Suspends until all are
     * acknowledged; returns how many settings were written. Nothing is written when the JSON does not parse.
     *
     * @throws IllegalArgumentException for malformed JSON, an unknown setting or a value of the wrong type.
     * @throws SettingRefusedException when the robot refuses a value (the writes before it stay written).
     */
    public suspend fun importJson(json: String): Int {
        val current = store.bytes.value
        val wanted = this.json.parse(json, current)
        val changed = SETTINGS_FIELDS.filter { f -> (f.offset until f.offset + f.size).any { wanted[it] != current[it] } }
        for (run in SettingsJson.runs(changed)) {
            val start = run.first().offset
            val data = wanted.copyOfRange(start, run.last().offset + run.last().size)
            try {
                linkPort.command(UpdateSettings(start, data))
            } catch (e: NotDriverException) {
                throw e // not the values: the robot takes no settings from a host that watches
            } catch (e: CommandRefusedException) {
                // The robot names the offending field by its offset; a range error names the start of the run.
                val culprit = run.firstOrNull { it.offset == e.detail } ?: run.first()
                val field = byName.getValue(culprit.path)
                throw SettingRefusedException(culprit.path, field.decode(wanted), e.code, e.detail, field.textOf(wanted), field.rangeText)
            }
            linkPort.serial { store.written(start, data) }
        }
        return changed.size
    }

    internal fun checkComplete() {
        val missing = SETTINGS_FIELDS.map { it.path }.filter { it !in byName }
        check(missing.isEmpty()) { "settings tree lacks $missing" }
    }
}

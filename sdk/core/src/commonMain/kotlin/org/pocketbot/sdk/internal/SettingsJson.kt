package org.pocketbot.sdk.internal

import kotlinx.serialization.ExperimentalSerializationApi
import kotlinx.serialization.json.Json
import kotlinx.serialization.json.JsonUnquotedLiteral
import kotlinx.serialization.json.JsonArray
import kotlinx.serialization.json.JsonElement
import kotlinx.serialization.json.JsonObject
import kotlinx.serialization.json.JsonPrimitive
import kotlinx.serialization.json.buildJsonObject
import kotlinx.serialization.json.doubleOrNull
import kotlinx.serialization.json.jsonObject
import kotlinx.serialization.json.longOrNull
import org.pocketbot.protocol.FieldType
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.SettingsFieldInfo
import org.pocketbot.sdk.EnumSetting
import org.pocketbot.sdk.toDecimalString

/**
 * Settings bytes to and from JSON grouped as in the protocol definition (`{"speed_pid": {"kp": 2500}}`). A float is
 * written as the shortest decimal that reads back to it (`0.0004`: a JSON number, exact), an enumeration setting by
 * its name (`"mode": "full"`; its code is read too). [enums] are the enumeration settings by name.
 */
internal class SettingsJson(private val enums: Map<String, EnumSetting<*>>) {
    private val json = Json { prettyPrint = true }

    @OptIn(ExperimentalSerializationApi::class)
    private fun number(f: SettingsFieldInfo, bytes: ByteArray, at: Int): JsonElement = when (val n = readNumber(bytes, at, f.type)) {
        is Float -> JsonUnquotedLiteral(n.toDecimalString())
        else -> JsonPrimitive(n)
    }

    private fun value(f: SettingsFieldInfo, bytes: ByteArray): JsonElement = when {
        f.type == FieldType.CHAR -> {
            var end = f.offset
            while (end < f.offset + f.count && bytes[end] != 0.toByte()) end++
            JsonPrimitive(bytes.decodeToString(f.offset, end))
        }
        f.count > 1 -> JsonArray(List(f.count) { number(f, bytes, f.offset + it * f.type.size) })
        else -> enums[f.path]?.nameOf(readNumber(bytes, f.offset, f.type).toInt())?.let(::JsonPrimitive) ?: number(f, bytes, f.offset)
    }

    fun export(bytes: ByteArray): String {
        val groups = LinkedHashMap<String, MutableMap<String, JsonElement>>()
        for (f in SETTINGS_FIELDS) {
            val (group, name) = f.path.split('.', limit = 2)
            groups.getOrPut(group) { LinkedHashMap() }[name] = value(f, bytes)
        }
        return json.encodeToString(JsonObject.serializer(), buildJsonObject { groups.forEach { (g, m) -> put(g, JsonObject(m)) } })
    }

    /** [base] with every field present in [text] replaced. */
    fun parse(text: String, base: ByteArray): ByteArray {
        val root = try {
            Json.parseToJsonElement(text).jsonObject
        } catch (e: Exception) {
            throw IllegalArgumentException("settings JSON is malformed: ${e.message}", e)
        }
        val out = base.copyOf()
        for ((group, members) in root) {
            val obj = members as? JsonObject ?: throw IllegalArgumentException("settings group \"$group\" is not an object")
            for ((name, v) in obj) {
                val path = "$group.$name"
                val f = SETTINGS_FIELDS.firstOrNull { it.path == path } ?: throw IllegalArgumentException("unknown setting $path")
                write(f, v, out)
            }
        }
        return out
    }

    private fun number(f: SettingsFieldInfo, v: JsonElement): Number {
        val p = v as? JsonPrimitive ?: throw IllegalArgumentException("${f.path} needs a number, not $v")
        enums[f.path]?.let { e ->
            if (p.isString) return e.codeOfName(p.content) ?: throw IllegalArgumentException("${f.path} is one of ${e.names.joinToString()}, not $v")
        }
        if (p.isString) throw IllegalArgumentException("${f.path} needs a number, not $v")
        return if (f.type == FieldType.F32) p.doubleOrNull ?: throw IllegalArgumentException("${f.path} needs a number, not $v")
        else p.longOrNull ?: throw IllegalArgumentException("${f.path} needs an integer, not $v")
    }

    private fun write(f: SettingsFieldInfo, v: JsonElement, out: ByteArray) {
        when {
            f.type == FieldType.CHAR -> {
                val p = v as? JsonPrimitive
                require(p != null && p.isString) { "${f.path} needs a string, not $v" }
                val raw = p.content.encodeToByteArray()
                require(raw.size <= f.count) { "${f.path} holds at most ${f.count} bytes" }
                out.fill(0, f.offset, f.offset + f.count)
                raw.copyInto(out, f.offset)
            }
            f.count > 1 -> {
                val a = v as? JsonArray ?: throw IllegalArgumentException("${f.path} needs an array of ${f.count}")
                require(a.size == f.count) { "${f.path} needs ${f.count} values, not ${a.size}" }
                a.forEachIndexed { i, e -> writeNumber(out, f.offset + i * f.type.size, f.type, number(f, e), f.path) }
            }
            else -> writeNumber(out, f.offset, f.type, number(f, v), f.path)
        }
    }

    companion object {
        /** [fields] (in struct order) split into runs of adjacent fields of at most 64 bytes each. */
        fun runs(fields: List<SettingsFieldInfo>): List<List<SettingsFieldInfo>> {
            val runs = ArrayList<MutableList<SettingsFieldInfo>>()
            for (f in fields.sortedBy { it.offset }) {
                val last = runs.lastOrNull()
                val end = last?.last()?.let { it.offset + it.size }
                if (last != null && end == f.offset && f.offset + f.size - last.first().offset <= 64) last += f
                else runs += mutableListOf(f)
            }
            return runs
        }
    }
}

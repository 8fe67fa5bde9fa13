package org.pocketbot.cli

import kotlinx.serialization.ExperimentalSerializationApi
import kotlinx.serialization.json.JsonArray
import kotlinx.serialization.json.JsonElement
import kotlinx.serialization.json.JsonNull
import kotlinx.serialization.json.JsonObject
import kotlinx.serialization.json.JsonPrimitive
import kotlinx.serialization.json.JsonUnquotedLiteral
import org.pocketbot.sdk.toDecimalString
import java.io.PrintStream

/** How results are printed: a table for people, one JSON object per line or CSV for scripts. */
enum class Format { TABLE, JSON, CSV }

/**
 * Prints rows of named values in the chosen [format]. A table is printed when [flush] is called (its columns are as
 * wide as their widest cell), or row by row after [stream]; JSON and CSV rows go out at once, so a stream
 * (`state --watch`) is usable line by line in every format.
 */
class Output(private val format: Format, private val out: PrintStream = System.out) {
    private val rows = mutableListOf<Map<String, Any?>>()
    private var csvHeader: List<String>? = null
    private var streamed: Map<String, Int>? = null

    /**
     * From now on a table row goes out as it comes, each column as wide as [widths] says (at least its title): a
     * stream's columns cannot wait for its widest cell. The header goes out at once. Nothing changes for JSON and CSV.
     */
    @Synchronized
    fun stream(widths: Map<String, Int>) {
        if (format != Format.TABLE) return
        flush()
        val columns = widths.mapValues { (name, w) -> maxOf(name.length, w) }
        streamed = columns
        out.println(columns.keys.joinToString("  ") { it.uppercase().padEnd(columns.getValue(it)) }.trimEnd())
        out.flush()
    }

    @Synchronized
    fun row(values: Map<String, Any?>) {
        val columns = streamed
        when {
            format == Format.TABLE && columns != null ->
                out.println(columns.entries.joinToString("  ") { (c, w) -> text(values[c]).padEnd(w) }.trimEnd())
            format == Format.TABLE -> rows += values
            format == Format.JSON -> out.println(JsonObject(values.mapValues { (_, v) -> json(v) }))
            else -> {
                val header = csvHeader ?: values.keys.toList().also { csvHeader = it; out.println(it.joinToString(",") { csv(it) }) }
                out.println(header.joinToString(",") { csv(text(values[it])) })
            }
        }
        out.flush()
    }

    fun row(vararg values: Pair<String, Any?>) = row(linkedMapOf(*values))

    /** Prints the table collected so far (nothing to do for JSON and CSV). */
    @Synchronized
    fun flush() {
        if (format != Format.TABLE || rows.isEmpty()) return
        val columns = rows.flatMap { it.keys }.distinct()
        val width = columns.associateWith { c -> maxOf(c.length, rows.maxOf { text(it[c]).length }) }
        out.println(columns.joinToString("  ") { it.uppercase().padEnd(width.getValue(it)) }.trimEnd())
        for (r in rows) out.println(columns.joinToString("  ") { text(r[it]).padEnd(width.getValue(it)) }.trimEnd())
        rows.clear()
        out.flush()
    }

    private fun text(v: Any?): String = when (v) {
        null -> ""
        is Double -> v.toDecimalString()
        is Float -> v.toDecimalString()
        is List<*> -> v.joinToString(" ") { text(it) }
        is Enum<*> -> v.name.lowercase()
        else -> v.toString()
    }

    private fun csv(s: String): String = if (s.any { it == ',' || it == '"' || it == '\n' }) "\"" + s.replace("\"", "\"\"") + "\"" else s

    @OptIn(ExperimentalSerializationApi::class)
    private fun json(v: Any?): JsonElement = when (v) {
        null -> JsonNull
        // The digits people read, as a number: exact for the robot's floats, never in scientific notation.
        is Double -> if (v.isFinite()) JsonUnquotedLiteral(v.toDecimalString()) else JsonNull
        is Float -> if (v.isFinite()) JsonUnquotedLiteral(v.toDecimalString()) else JsonNull
        is Number -> JsonPrimitive(v)
        is Boolean -> JsonPrimitive(v)
        is List<*> -> JsonArray(v.map { json(it) })
        is Enum<*> -> JsonPrimitive(v.name.lowercase())
        else -> JsonPrimitive(v.toString())
    }
}

package org.pocketbot.sdk.it

import org.junit.jupiter.api.Test
import org.pocketbot.sdk.StateFields
import java.io.File
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith

/** The SDK's named state fields follow the protocol definition, field for field. */
class StateFieldsTest {
    /** Every leaf of the schema's robot state in struct order: its dotted name, wire type and `enum:<name>` or `flags:<name>` (or null). */
    private fun schemaLeaves(): List<Triple<String, String, String?>> {
        val toml = File("../../protocol/pocketbot.toml").readText()
        val fieldLine = Regex("""\{ name = "([a-z_0-9]+)", type = "([a-z_0-9\[\]]+)"(?:[^}]*?((?:enum|flags) = "[a-z_]+"))?""")
        fun leaves(body: String) = fieldLine.findAll(body).map { m ->
            Triple(m.groupValues[1], m.groupValues[2], m.groupValues[3].ifEmpty { null }?.replace(" = ", ":")?.replace("\"", ""))
        }.toList()
        val structs = Regex("""\[struct\.([a-z_]+)\][^\[]*?fields = \[(.*?)\n\]""", RegexOption.DOT_MATCHES_ALL).findAll(toml)
            .associate { m -> m.groupValues[1] to leaves(m.groupValues[2]) }
        return Regex("""\[\[state\]\]\s*name = "([a-z_]+)".*?fields = \[(.*?)\n\]""", RegexOption.DOT_MATCHES_ALL).findAll(toml)
            .flatMap { group ->
                leaves(group.groupValues[2]).flatMap { (name, type, enum) ->
                    val path = "${group.groupValues[1]}.$name"
                    structs[type]?.map { (n, t, e) -> Triple("$path.$n", t, e) } ?: listOf(Triple(path, type, enum))
                }
            }.toList()
    }

    @Test
    fun everyFieldOfTheRobotStateInTheSchemaHasItsNameInStructOrder() {
        assertEquals(schemaLeaves().map { it.first }, StateFields.all.map { it.name })
    }

    @Test
    fun eachFieldIsAsWideAsTheWidestTextOfItsWireType() {
        val toml = File("../../protocol/pocketbot.toml").readText()
        fun enumWidth(enum: String): Int {
            val values = Regex("""\[enum\.$enum\][^\[]*?values = \{([^}]*)\}""").find(toml)!!.groupValues[1]
            // A code this side does not know reads as "unknown".
            return (Regex("""([a-z_]+) =""").findAll(values).map { it.groupValues[1] } + "unknown").maxOf { it.length }
        }
        // A flags field reads as the names of its bits set, joined by '+': at most all of them.
        fun flagsWidth(flags: String): Int {
            val values = Regex("""\[flags\.$flags\][^\[]*?values = \{([^}]*)\}""").find(toml)!!.groupValues[1]
            return Regex("""([a-z_]+) =""").findAll(values).sumOf { it.groupValues[1].length + 1 } - 1
        }
        fun numberWidth(type: String): Int = when (type) {
            "u8" -> "255".length
            "u16" -> "65535".length
            "i16" -> "-32768".length
            "u32" -> "4294967295".length
            "i32" -> "-2147483648".length
            else -> error("no width for $type")
        }
        val widths = StateFields.all.associate { it.name to it.width }
        for ((name, type, enum) in schemaLeaves()) {
            val array = Regex("""([a-z0-9]+)\[(\d+)\]""").matchEntire(type)
            val expected = when {
                enum != null && enum.startsWith("flags:") -> flagsWidth(enum.removePrefix("flags:"))
                enum != null -> enumWidth(enum.removePrefix("enum:"))
                array != null -> array.groupValues[2].toInt() * (numberWidth(array.groupValues[1]) + 1) - 1
                else -> numberWidth(type)
            }
            assertEquals(expected, widths[name], "width of $name ($type${enum?.let { ", enum $it" } ?: ""})")
        }
    }

    @Test
    fun groupsSelectTheirFieldsAndUnknownNamesAreRefused() {
        assertEquals(listOf("wheels.speed_left_mmps", "wheels.speed_right_mmps", "wheels.pwm_left", "wheels.pwm_right", "line.position"),
            StateFields.select(listOf("wheels", "line.position")).map { it.name })
        assertFailsWith<IllegalArgumentException> { StateFields.select(listOf("wheel")) }
    }
}

package org.pocketbot.sdk

import kotlin.random.Random
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/** Numbers as people read them: the shortest decimal that reads back to the robot's float, never an exponent. */
class DecimalTextTest {
    @Test
    fun floatsReadAsTheShortestPlainDecimalThatReadsBack() {
        val cases = mapOf(
            0.0004f to "0.0004", 0.15f to "0.15", 0.1f to "0.1", 2f to "2", 0f to "0", -0.5f to "-0.5", 2500f to "2500",
            100000f to "100000", 1e-7f to "0.0000001", 123456.78f to "123456.78", 1.0000001f to "1.0000001",
            16777216f to "16777216", 3.4028235e38f to "340282350000000000000000000000000000000", 0.002f to "0.002",
        )
        for ((value, text) in cases) assertEquals(text, value.toDecimalString(), "$value")
    }

    @Test
    fun everyFloatReadsBackFromItsText() {
        val random = Random(21)
        repeat(20_000) {
            val f = Float.fromBits(random.nextInt())
            if (f.isNaN() || f.isInfinite()) return@repeat
            val text = f.toDecimalString()
            assertTrue('e' !in text && 'E' !in text, "$f as $text")
            assertEquals(f.toRawBits().let { if (f == 0f) 0 else it }, text.toDouble().toFloat().toRawBits().let { if (f == 0f) 0 else it }, "$f as $text")
            assertTrue(significant(text) <= 9, "$f as $text: more digits than a float has")
        }
        // Gains people type: each reads as typed.
        for (typed in listOf("0.0004", "1.5", "0.75", "2500", "0.002", "40", "0.333", "12.5")) assertEquals(typed, typed.toFloat().toDecimalString())
    }

    /** How many significant digits [text] has. */
    private fun significant(text: String): Int = text.removePrefix("-").replace(".", "").trimStart('0').trimEnd('0').length

    @Test
    fun doublesReadInPlainNotation() {
        val cases = mapOf(1e5 to "100000", 2.5e-4 to "0.00025", 0.01 to "0.01", 20.0 to "20", -3.0 to "-3", 0.0 to "0", 1e21 to "1000000000000000000000")
        for ((value, text) in cases) assertEquals(text, value.toDecimalString(), "$value")
    }
}

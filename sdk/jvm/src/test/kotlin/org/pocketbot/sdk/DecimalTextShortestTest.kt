package org.pocketbot.sdk

import java.math.BigDecimal
import java.math.MathContext
import java.math.RoundingMode
import kotlin.random.Random
import kotlin.test.Test
import kotlin.test.assertTrue

/** The text of a float is never longer than the nearest decimal of fewest digits that reads back (exact arithmetic). */
class DecimalTextShortestTest {
    @Test
    fun noDecimalWithFewerDigitsReadsBackToTheFloat() {
        val random = Random(22)
        repeat(50_000) {
            val f = Float.fromBits(random.nextInt()).takeIf { it.isFinite() && it != 0f } ?: return@repeat
            val exact = BigDecimal(f.toDouble())
            val shortest = (1..9).first { p -> exact.round(MathContext(p, RoundingMode.HALF_EVEN)).toDouble().toFloat() == f }
            val digits = f.toDecimalString().removePrefix("-").replace(".", "").trimStart('0').trimEnd('0').length
            assertTrue(digits <= shortest, "$f: ${f.toDecimalString()} has $digits digits, $shortest do")
        }
    }
}

package org.pocketbot.desktop.ui

import androidx.compose.runtime.Composable
import androidx.compose.runtime.State
import androidx.compose.runtime.produceState
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.StateFlow
import java.math.BigDecimal
import java.math.RoundingMode
import kotlin.random.Random

/** How often a number people read (a counter, a speed) may change on screen: they cannot read it faster. */
const val HUMAN_PERIOD_MS = 250L

/**
 * This flow's value for text people read, at most every [HUMAN_PERIOD_MS]: a change after a quiet spell shows at once,
 * a stream of them (link counters, state at 100 Hz) as its newest value four times a second. Recomposing, laying out
 * and drawing such text at the robot's rate costs a frame's budget and shows nothing more.
 */
@Composable
fun <T> StateFlow<T>.collectAtHumanRate(): State<T> = produceState(value, this) {
    // Each from its own moment in the period: a fleet's rows, started together, would otherwise all change in the
    // same frame four times a second, and that frame would take the work of all of them.
    delay(Random.nextLong(HUMAN_PERIOD_MS))
    collect {
        value = it
        delay(HUMAN_PERIOD_MS)
    }
}

/**
 * [value] with [places] decimals, rounded half up, with a point: what `"%.2f".format(value)` writes in the root locale
 * (but "0.00" for a negative value that rounds to zero), for rows a fleet rewrites many times a second: String.format
 * looks up the locale's symbols and parses its pattern each time, and costs more than the rest of such a row.
 */
fun decimals(value: Double, places: Int): String =
    if (value.isFinite()) BigDecimal.valueOf(value).setScale(places, RoundingMode.HALF_UP).toPlainString() else value.toString()

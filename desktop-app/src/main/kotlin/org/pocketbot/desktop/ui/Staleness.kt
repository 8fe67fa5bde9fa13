package org.pocketbot.desktop.ui

import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.padding
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.Surface
import androidx.compose.material3.Text
import androidx.compose.runtime.Composable
import androidx.compose.runtime.getValue
import androidx.compose.runtime.produceState
import androidx.compose.ui.Modifier
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.semantics.semantics
import androidx.compose.ui.semantics.stateDescription
import androidx.compose.ui.unit.dp
import kotlinx.coroutines.delay
import org.pocketbot.sdk.Freshness
import org.pocketbot.sdk.StaleReason
import org.pocketbot.sdk.StateFreshness
import kotlin.time.TimeMark

/** Marks a value that is not live (see [Freshness]) for tests and screen readers; [valueColour] greys it. */
fun Modifier.stale(stale: Boolean): Modifier = if (stale) semantics { stateDescription = "stale" } else this

@Composable
fun valueColour(stale: Boolean): Color = if (stale) MaterialTheme.colorScheme.onSurfaceVariant.copy(alpha = 0.5f) else Color.Unspecified

/** Whole seconds since [mark], counted on once a second while shown; null without a mark. */
@Composable
fun secondsSince(mark: TimeMark?): Long? {
    val seconds by produceState(mark?.elapsedNow()?.inWholeSeconds, mark) {
        while (mark != null) {
            value = mark.elapsedNow().inWholeSeconds
            delay(1000 - mark.elapsedNow().inWholeMilliseconds % 1000)
        }
    }
    return seconds
}

/** "as of 25 s ago, link lost": how old values that are not live are, and why; empty while they are live. */
@Composable
fun asOf(f: Freshness): String {
    if (f.isLive) return ""
    val seconds = secondsSince(f.heardAt)
    return listOfNotNull(seconds?.let { "as of $it s ago" }, why(f.staleBecause)).joinToString(", ")
}

/** Why values are not live, in words. */
fun why(reason: StaleReason?): String? = when (reason) {
    null -> null
    StaleReason.NOT_YET -> "nothing heard yet"
    StaleReason.LINK_DOWN -> "link lost"
    StaleReason.NOT_SENT -> "not in reduced sync"
    StaleReason.SILENT -> "the robot went quiet"
}

/**
 * Says which values are not live and since when: the link is down, the robot sends reduced state (as PID tuning asks
 * for: robot time, encoders, wheel speeds and the line position stay live) or none, or it went quiet. Nothing while
 * all are live.
 */
@Composable
fun StaleBanner(f: StateFreshness) {
    if (f.full.isLive) return
    val all = f.reduced
    val text = when (if (all.isLive) null else all.staleBecause) {
        null -> "Reduced state (as PID tuning asks for): robot time, encoders, wheel speeds and the line position are live; the greyed values are ${since(f.full)}."
        StaleReason.NOT_SENT -> "The robot sends no state (sync mode none): every value is ${since(all)}."
        StaleReason.LINK_DOWN -> "The link is down: every value is ${since(all)}."
        StaleReason.SILENT -> "The robot has sent nothing for a while: every value is ${since(all)}."
        StaleReason.NOT_YET -> "No state from the robot since the link came up: every value is ${since(all)}."
    }
    Surface(color = MaterialTheme.colorScheme.tertiaryContainer, shape = MaterialTheme.shapes.small) {
        Text(text, Modifier.fillMaxWidth().padding(8.dp).testTag("stale-banner"), style = MaterialTheme.typography.bodySmall)
    }
}

/** "from 25 s ago (robot time 46.7 s)": when values that are not live were heard. */
@Composable
private fun since(f: Freshness): String {
    val seconds = secondsSince(f.heardAt) ?: return "from before the first state"
    return "from $seconds s ago" + (f.robotTimeMs?.let { " (robot time %.1f s)".format(it / 1000.0) } ?: "")
}

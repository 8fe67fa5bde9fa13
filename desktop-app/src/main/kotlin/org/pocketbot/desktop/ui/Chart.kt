package org.pocketbot.desktop.ui

import androidx.compose.foundation.Canvas
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.Spacer
import androidx.compose.foundation.layout.size
import androidx.compose.foundation.background
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.Text
import androidx.compose.runtime.Composable
import androidx.compose.ui.Alignment
import androidx.compose.ui.Modifier
import androidx.compose.ui.geometry.Offset
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.semantics.contentDescription
import androidx.compose.ui.semantics.semantics
import androidx.compose.ui.graphics.Path
import androidx.compose.ui.graphics.PathEffect
import androidx.compose.ui.graphics.drawscope.DrawScope
import androidx.compose.ui.graphics.drawscope.Stroke
import androidx.compose.ui.text.TextMeasurer
import androidx.compose.ui.text.TextStyle
import androidx.compose.ui.text.drawText
import androidx.compose.ui.text.rememberTextMeasurer
import androidx.compose.ui.unit.dp
import androidx.compose.ui.unit.sp
import kotlin.math.abs
import kotlin.math.floor
import kotlin.math.log10
import kotlin.math.pow

/** One line of a [LineChart]: x and y of each point, same length. */
class Series(val label: String, val x: DoubleArray, val y: DoubleArray, val colour: Color, val dashed: Boolean = false)

/**
 * A line chart drawn straight on a Canvas: axes with round ticks, one path per series. A few thousand points per
 * frame cost well under a millisecond, so the tuning chart can redraw every frame without thinning its samples.
 */
@Composable
fun LineChart(series: List<Series>, xLabel: String, modifier: Modifier = Modifier, yRange: ClosedFloatingPointRange<Double>? = null) {
    val measurer = rememberTextMeasurer(cacheSize = 64) // every tick label of both charts stays laid out between frames
    val axis = MaterialTheme.colorScheme.onSurfaceVariant
    Column(modifier.semantics { contentDescription = "chart of " + series.joinToString { "${it.label} (${it.x.size} points)" } }) {
        Canvas(Modifier.weight(1f).fillMaxWidth()) { drawChart(series, xLabel, yRange, measurer, axis) }
        Row(verticalAlignment = Alignment.CenterVertically) {
            for (s in series) {
                Spacer(Modifier.size(12.dp, 3.dp).background(s.colour))
                Text(" ${s.label}    ", style = MaterialTheme.typography.bodySmall)
            }
        }
    }
}

fun DrawScope.drawChart(series: List<Series>, xLabel: String, yRange: ClosedFloatingPointRange<Double>?, measurer: TextMeasurer, axis: Color) {
    val left = 56f
    val bottom = 26f
    val w = size.width - left - 8f
    val h = size.height - bottom - 8f
    if (w <= 0 || h <= 0) return
    val xs = series.filter { it.x.isNotEmpty() }
    val xMin = xs.minOfOrNull { it.x.first() } ?: 0.0
    val xMax = (xs.maxOfOrNull { it.x.last() } ?: 1.0).let { if (it <= xMin) xMin + 1 else it }
    var yMin = yRange?.start ?: xs.minOfOrNull { s -> s.y.minOrNull() ?: 0.0 } ?: 0.0
    var yMax = yRange?.endInclusive ?: xs.maxOfOrNull { s -> s.y.maxOrNull() ?: 1.0 } ?: 1.0
    if (yMax - yMin < 1e-9) { yMin -= 0.5; yMax += 0.5 }
    val pad = (yMax - yMin) * 0.08
    yMin -= pad; yMax += pad
    fun px(x: Double) = left + ((x - xMin) / (xMax - xMin) * w).toFloat()
    fun py(y: Double) = 8f + h - ((y - yMin) / (yMax - yMin) * h).toFloat()
    val style = TextStyle(fontSize = 10.sp, color = axis)
    for (t in ticks(yMin, yMax)) {
        drawLine(Color(0x22000000), Offset(left, py(t)), Offset(left + w, py(t)))
        drawText(measurer, format(t), Offset(2f, py(t) - 7f), style)
    }
    for (t in ticks(xMin, xMax)) {
        drawLine(Color(0x22000000), Offset(px(t), 8f), Offset(px(t), 8f + h))
        drawText(measurer, format(t), Offset(px(t) - 10f, 8f + h + 4f), style)
    }
    drawText(measurer, xLabel, Offset(left + w - 60f, 8f + h + 4f), style)
    drawLine(axis, Offset(left, 8f), Offset(left, 8f + h))
    drawLine(axis, Offset(left, 8f + h), Offset(left + w, 8f + h))
    for (s in xs) {
        val path = Path()
        for (i in s.x.indices) {
            val p = Offset(px(s.x[i]), py(s.y[i]))
            if (i == 0) path.moveTo(p.x, p.y) else path.lineTo(p.x, p.y)
        }
        drawPath(path, s.colour, style = Stroke(width = 2f, pathEffect = if (s.dashed) PathEffect.dashPathEffect(floatArrayOf(8f, 6f)) else null))
    }
}

/** Round tick values between [min] and [max], about five of them. */
fun ticks(min: Double, max: Double): List<Double> {
    val span = max - min
    if (span <= 0 || !span.isFinite()) return emptyList()
    val raw = span / 5
    val mag = 10.0.pow(floor(log10(raw)))
    val step = listOf(1.0, 2.0, 5.0, 10.0).map { it * mag }.first { it >= raw }
    val first = kotlin.math.ceil(min / step) * step
    return generateSequence(first) { it + step }.takeWhile { it <= max + step * 1e-9 }.toList()
}

private fun format(v: Double): String = when {
    abs(v) < 1e-12 -> "0"
    abs(v) >= 100 -> "%.0f".format(v)
    abs(v) >= 1 -> "%.1f".format(v)
    else -> "%.3f".format(v).trimEnd('0')
}

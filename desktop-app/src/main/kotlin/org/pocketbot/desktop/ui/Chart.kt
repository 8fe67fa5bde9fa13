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
import androidx.compose.ui.graphics.drawscope.DrawScope
import androidx.compose.ui.graphics.drawscope.drawIntoCanvas
import androidx.compose.ui.graphics.graphicsLayer
import androidx.compose.ui.graphics.nativeCanvas
import androidx.compose.ui.graphics.toArgb
import org.jetbrains.skia.PaintMode
import androidx.compose.ui.text.TextMeasurer
import androidx.compose.ui.text.TextStyle
import androidx.compose.ui.text.drawText
import androidx.compose.ui.text.rememberTextMeasurer
import androidx.compose.ui.unit.dp
import androidx.compose.ui.unit.sp
import kotlin.math.abs
import kotlin.math.floor
import kotlin.math.log10
import kotlin.math.max
import kotlin.math.min
import kotlin.math.pow

/** One line of a [LineChart]: x and y of each point, same length. */
class Series(val label: String, val x: DoubleArray, val y: DoubleArray, val colour: Color, val dashed: Boolean = false)

/** A chart of [series] that do not change while it is shown; its description counts their points. */
@Composable
fun LineChart(series: List<Series>, xLabel: String, modifier: Modifier = Modifier, yRange: ClosedFloatingPointRange<Double>? = null) =
    LineChart({ series }, series.map { it.label to it.colour }, "chart of " + series.joinToString { "${it.label} (${it.x.size} points)" }, xLabel, modifier, yRange)

/**
 * A line chart drawn straight on a Canvas: axes with round ticks, each series drawn by the pixel columns it covers
 * ([ColumnSpans]), so a live chart redraws every frame from all its samples at a cost set by its width. [series] is
 * read while drawing only: a live chart's new samples redraw its canvas and nothing else (no recomposition, no
 * layout); [legend] names the series (label and colour each) and [description] says what the chart shows.
 */
@Composable
fun LineChart(
    series: () -> List<Series>, legend: List<Pair<String, Color>>, description: String, xLabel: String, modifier: Modifier = Modifier,
    yRange: ClosedFloatingPointRange<Double>? = null,
) {
    val measurer = rememberTextMeasurer(cacheSize = 64) // every tick label of both charts stays laid out between frames
    val axis = MaterialTheme.colorScheme.onSurfaceVariant
    Column(modifier.semantics { contentDescription = description }) {
        // Its own layer: a live chart redraws every frame, and the views around it need not record theirs again.
        Canvas(Modifier.weight(1f).fillMaxWidth().graphicsLayer()) { drawChart(series(), xLabel, yRange, measurer, axis) }
        Row(verticalAlignment = Alignment.CenterVertically) {
            for ((label, colour) in legend) {
                Spacer(Modifier.size(12.dp, 3.dp).background(colour))
                Text(" $label    ", style = MaterialTheme.typography.bodySmall)
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
    val spans = ColumnSpans(w.toInt())
    for (s in xs) {
        spans.trace(FloatArray(s.x.size) { px(s.x[it]) - left }, FloatArray(s.y.size) { py(s.y[it]) })
        seriesPaint.color = s.colour.toArgb()
        drawIntoCanvas { it.nativeCanvas.drawLines(spans.lines(left, if (s.dashed) DASH_PX else 0), seriesPaint) }
    }
}

private const val DASH_PX = 6

/** Aliased hairlines: a series is drawn as vertical 1 px lines, two per pixel column it covers. */
private val seriesPaint = org.jetbrains.skia.Paint().apply {
    mode = PaintMode.STROKE
    strokeWidth = 0f
    isAntiAlias = false
}

/**
 * A polyline as the pixel columns it covers: for each column of the plot, the lowest and the highest y the line
 * passes through there, from every point and every segment between points. Drawn as a vertical bar per column (2 px
 * wide, 1 px beyond the span above and below), it looks like the line stroked 2 px wide and keeps every peak of every
 * sample, but costs the same however many samples fall into a column: Skia's software rasterizer takes several
 * milliseconds to stroke a 2 px anti-aliased path through a thousand noisy samples, and a tenth of one for these bars.
 */
class ColumnSpans(val columns: Int) {
    /** Per column, the lowest and highest y covered (pixels, y down); lo > hi where the line does not pass. */
    val lo = FloatArray(columns.coerceAtLeast(0))
    val hi = FloatArray(columns.coerceAtLeast(0))

    /**
     * Covers the polyline through the points ([x] in pixels from the plot's left, ascending; [y] in pixels); a point
     * with a non-finite coordinate breaks the line.
     */
    fun trace(x: FloatArray, y: FloatArray) {
        lo.fill(Float.POSITIVE_INFINITY)
        hi.fill(Float.NEGATIVE_INFINITY)
        if (columns <= 0) return
        var previous = -1
        for (i in x.indices) {
            if (!x[i].isFinite() || !y[i].isFinite()) { previous = -1; continue }
            if (previous < 0) cover(x[i], y[i], x[i], y[i]) else cover(x[previous], y[previous], x[i], y[i])
            previous = i
        }
    }

    /** The segment from (x0, y0) to (x1, y1), x0 <= x1: each column it crosses gets the part of it inside that column. */
    private fun cover(x0: Float, y0: Float, x1: Float, y1: Float) {
        val first = floor(x0).toInt().coerceIn(0, columns - 1)
        val last = floor(x1).toInt().coerceIn(0, columns - 1)
        val slope = if (x1 > x0) (y1 - y0) / (x1 - x0) else 0f
        for (c in first..last) {
            val ys = if (c == first) y0 else y0 + slope * (c - x0)
            val ye = if (c == last) y1 else y0 + slope * (c + 1 - x0)
            lo[c] = min(lo[c], min(ys, ye))
            hi[c] = max(hi[c], max(ys, ye))
        }
    }

    /**
     * The covered columns as line segments (x0, y0, x1, y1 each) for [org.jetbrains.skia.Canvas.drawLines], offset by
     * [left]: two vertical ones per column, at its pixel and the next; every other run of [dash] columns is left out
     * when [dash] > 0.
     */
    fun lines(left: Float, dash: Int = 0): FloatArray {
        val out = FloatArray(8 * columns)
        var n = 0
        for (c in 0 until columns) {
            if (lo[c] > hi[c] || (dash > 0 && (c / dash) % 2 == 1)) continue
            for (dx in 0..1) {
                val x = left + c + dx + 0.5f
                out[n++] = x; out[n++] = lo[c] - 1f; out[n++] = x; out[n++] = hi[c] + 1f
            }
        }
        return out.copyOf(n)
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

/** Tick labels, formatted once: String.format costs more than drawing the label from the text layout cache. */
private val labels = HashMap<Double, String>()

private fun format(v: Double): String = labels[v] ?: formatNew(v).also { if (labels.size > 512) labels.clear(); labels[v] = it }

private fun formatNew(v: Double): String = when {
    abs(v) < 1e-12 -> "0"
    abs(v) >= 100 -> "%.0f".format(v)
    abs(v) >= 1 -> "%.1f".format(v)
    else -> "%.3f".format(v).trimEnd('0')
}

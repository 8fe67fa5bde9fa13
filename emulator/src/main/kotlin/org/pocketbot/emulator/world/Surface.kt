package org.pocketbot.emulator.world

import kotlin.math.PI
import kotlin.math.atan2
import kotlin.math.ceil
import kotlin.math.cos
import kotlin.math.floor
import kotlin.math.hypot
import kotlin.math.max
import kotlin.math.min
import kotlin.math.sin
import kotlin.math.sqrt

/**
 * The floor of a [World] prepared for fast queries: every tape piece is a segment or an arc with round
 * ends, indexed in a uniform grid, so a sensor spot costs one cell lookup and a couple of distance tests.
 * Immutable and safe to read from any thread.
 */
public class Surface(world: World) {
    private val cell = CELL_M
    private val inverseCell = 1.0 / CELL_M
    private val cols: Int = max(1, ceil(world.widthM / cell).toInt())
    private val rows: Int = max(1, ceil(world.heightM / cell).toInt())

    // Pieces in paint order, struct-of-arrays.
    private val kind: IntArray
    private val ax: DoubleArray; private val ay: DoubleArray
    private val bx: DoubleArray; private val by: DoubleArray
    private val radius: DoubleArray; private val start: DoubleArray; private val sweep: DoubleArray
    private val halfWidth: DoubleArray
    private val colour: Array<TapeColour>
    // Per piece: IR darkness of its colour, and whether it is a whole circle (distance = |rho - r|).
    private val darkness: DoubleArray
    private val fullCircle: BooleanArray
    // The grid flattened: pieces of cell c are cellItems[cellStart[c] until cellStart[c + 1]].
    private val cellStart: IntArray
    private val cellItems: IntArray
    // Cells holding the same pieces in the same order share a number: spots in two such cells are done together.
    private val cellGroup: IntArray

    init {
        val pieces = ArrayList<Piece>()
        for (tape in world.tapes) when (tape) {
            is Tape.Polyline -> {
                val pts = tape.points
                val n = if (tape.closed) pts.size else pts.size - 1
                for (i in 0 until n) {
                    val a = pts[i]; val b = pts[(i + 1) % pts.size]
                    pieces += Piece(SEGMENT, a.x, a.y, b.x, b.y, 0.0, 0.0, 0.0, tape.widthM / 2, tape.colour)
                }
            }
            is Tape.Arc -> pieces += Piece(
                ARC, tape.center.x, tape.center.y, 0.0, 0.0, tape.radiusM,
                Math.toRadians(tape.startDeg), Math.toRadians(tape.sweepDeg), tape.widthM / 2, tape.colour,
            )
        }
        kind = IntArray(pieces.size) { pieces[it].kind }
        ax = DoubleArray(pieces.size) { pieces[it].ax }; ay = DoubleArray(pieces.size) { pieces[it].ay }
        bx = DoubleArray(pieces.size) { pieces[it].bx }; by = DoubleArray(pieces.size) { pieces[it].by }
        radius = DoubleArray(pieces.size) { pieces[it].r }
        start = DoubleArray(pieces.size) { pieces[it].start }
        sweep = DoubleArray(pieces.size) { pieces[it].sweep }
        halfWidth = DoubleArray(pieces.size) { pieces[it].hw }
        colour = Array(pieces.size) { pieces[it].colour }
        darkness = DoubleArray(pieces.size) { colour[it].irDarkness }
        fullCircle = BooleanArray(pieces.size) { kind[it] == ARC && kotlin.math.abs(sweep[it]) >= 2 * PI }

        val lists = arrayOfNulls<ArrayList<Int>>(cols * rows)
        val reach = MAX_SPOT_RADIUS_M + cell * 0.71
        for (p in pieces.indices) {
            val hw = halfWidth[p] + reach
            val (x0, y0, x1, y1) = when (kind[p]) {
                SEGMENT -> listOf(min(ax[p], bx[p]) - hw, min(ay[p], by[p]) - hw, max(ax[p], bx[p]) + hw, max(ay[p], by[p]) + hw)
                else -> listOf(ax[p] - radius[p] - hw, ay[p] - radius[p] - hw, ax[p] + radius[p] + hw, ay[p] + radius[p] + hw)
            }
            for (cy in clampRow(y0)..clampRow(y1)) for (cx in clampCol(x0)..clampCol(x1)) {
                val mx = (cx + 0.5) * cell; val my = (cy + 0.5) * cell
                if (distance(p, mx, my) <= hw) (lists[cy * cols + cx] ?: ArrayList<Int>().also { lists[cy * cols + cx] = it }) += p
            }
        }
        cellStart = IntArray(cols * rows + 1)
        for (c in 0 until cols * rows) cellStart[c + 1] = cellStart[c] + (lists[c]?.size ?: 0)
        cellItems = IntArray(cellStart[cols * rows])
        for (c in 0 until cols * rows) lists[c]?.forEachIndexed { k, p -> cellItems[cellStart[c] + k] = p }
        val groups = HashMap<List<Int>, Int>()
        cellGroup = IntArray(cols * rows) { c -> groups.getOrPut(lists[c].orEmpty()) { groups.size } }
    }

    /** Number of tape pieces (segments and arcs). */
    public val pieceCount: Int get() = kind.size

    /**
     * Infrared darkness (0 white floor .. 1 black tape) seen by a round spot of radius [spotRadiusM] centred
     * at ([x], [y]): the tape pieces are blended in paint order by how much of the spot each covers.
     */
    public fun irDarkness(x: Double, y: Double, spotRadiusM: Double): Double {
        // The line sensor asks eight times per simulated millisecond per robot: kept lean (the same
        // arithmetic as coverage(), with the whole-circle distance inline).
        val cx = floor(x * inverseCell).toInt(); val cy = floor(y * inverseCell).toInt()
        if (cx < 0 || cy < 0 || cx >= cols || cy >= rows) return 0.0
        val cell = cy * cols + cx
        var k = cellStart[cell]
        val end = cellStart[cell + 1]
        var dark = 0.0
        while (k < end) {
            val p = cellItems[k++]
            val d = if (fullCircle[p]) {
                val rx = x - ax[p]; val ry = y - ay[p]
                kotlin.math.abs(sqrt(rx * rx + ry * ry) - radius[p])
            } else distance(p, x, y)
            val hw = halfWidth[p]
            if (d >= hw + spotRadiusM) continue
            val lo = max(d - spotRadiusM, -hw); val hi = min(d + spotRadiusM, hw)
            val c = ((hi - lo) / (2 * spotRadiusM)).coerceIn(0.0, 1.0)
            if (c > 0.0) dark += (darkness[p] - dark) * c
        }
        return dark
    }

    /**
     * [irDarkness] of [n] spots at ([xs], [ys]) into [out], with exactly the same results. When every spot's cell
     * holds the same pieces (nearly always: the line sensor's spots are 2.5 mm apart), the spots are done
     * together, piece by piece in paint order, so their independent square roots and divisions overlap.
     */
    public fun irDarknessSpots(xs: DoubleArray, ys: DoubleArray, n: Int, spotRadiusM: Double, out: DoubleArray) {
        val c0 = cellIndex(xs[0], ys[0])
        if (c0 < 0) { for (j in 0 until n) out[j] = irDarkness(xs[j], ys[j], spotRadiusM); return }
        val k0 = cellStart[c0]
        val len = cellStart[c0 + 1] - k0
        val group = cellGroup[c0]
        for (j in 1 until n) {
            val c = cellIndex(xs[j], ys[j])
            if (c == c0) continue
            if (c < 0 || cellGroup[c] != group) {
                for (i in 0 until n) out[i] = irDarkness(xs[i], ys[i], spotRadiusM)
                return
            }
        }
        for (j in 0 until n) out[j] = 0.0
        for (k in k0 until k0 + len) {
            val p = cellItems[k]
            val hw = halfWidth[p]
            val dk = darkness[p]
            val reach = hw + spotRadiusM
            val full = fullCircle[p]
            val cx = ax[p]; val cy = ay[p]; val r = radius[p]
            for (j in 0 until n) {
                val x = xs[j]; val y = ys[j]
                val d = if (full) {
                    val rx = x - cx; val ry = y - cy
                    kotlin.math.abs(sqrt(rx * rx + ry * ry) - r)
                } else distance(p, x, y)
                if (d >= reach) continue
                val lo = max(d - spotRadiusM, -hw); val hi = min(d + spotRadiusM, hw)
                val c = ((hi - lo) / (2 * spotRadiusM)).coerceIn(0.0, 1.0)
                if (c > 0.0) out[j] += (dk - out[j]) * c
            }
        }
    }

    /** Colour under a spot, blended like [irDarkness]; writes r, g, b (0..255) into [out]. */
    public fun colourAt(x: Double, y: Double, spotRadiusM: Double, out: DoubleArray) {
        var r = TapeColour.WHITE.r.toDouble(); var g = TapeColour.WHITE.g.toDouble(); var b = TapeColour.WHITE.b.toDouble()
        val cell = cellIndex(x, y)
        if (cell >= 0) for (k in cellStart[cell] until cellStart[cell + 1]) {
            val p = cellItems[k]
            val c = coverage(p, x, y, spotRadiusM)
            if (c > 0.0) {
                val col = colour[p]
                r += (col.r - r) * c; g += (col.g - g) * c; b += (col.b - b) * c
            }
        }
        out[0] = r; out[1] = g; out[2] = b
    }

    /** The colour of the topmost tape whose centre line is within its half width of the point, or WHITE. */
    public fun tapeAt(x: Double, y: Double): TapeColour {
        var result = TapeColour.WHITE
        for (p in cellAt(x, y)) if (distance(p, x, y) <= halfWidth[p]) result = colour[p]
        return result
    }

    /** Distance from the point to the nearest tape centre line of [colourFilter] (any when null), or +inf. */
    public fun distanceToTape(x: Double, y: Double, colourFilter: TapeColour? = null): Double {
        var best = Double.POSITIVE_INFINITY
        for (p in kind.indices) if (colourFilter == null || colour[p] == colourFilter) best = min(best, distance(p, x, y))
        return best
    }

    /** Distance from the point to the nearest edge of any tape, 0 or less on the tape. */
    public fun distanceToTapeEdge(x: Double, y: Double): Double {
        var best = Double.POSITIVE_INFINITY
        for (p in kind.indices) best = min(best, distance(p, x, y) - halfWidth[p])
        return best
    }

    private fun cellIndex(x: Double, y: Double): Int {
        val cx = floor(x * inverseCell).toInt(); val cy = floor(y * inverseCell).toInt()
        if (cx < 0 || cy < 0 || cx >= cols || cy >= rows) return -1
        return cy * cols + cx
    }

    private fun cellAt(x: Double, y: Double): IntArray {
        val c = cellIndex(x, y)
        return if (c < 0) EMPTY else cellItems.copyOfRange(cellStart[c], cellStart[c + 1])
    }

    private fun clampCol(x: Double) = floor(x / cell).toInt().coerceIn(0, cols - 1)
    private fun clampRow(y: Double) = floor(y / cell).toInt().coerceIn(0, rows - 1)

    /** Fraction of a spot of radius r at distance d from the centre line covered by the tape (1D overlap across it). */
    private fun coverage(p: Int, x: Double, y: Double, r: Double): Double {
        val d = distance(p, x, y)
        val hw = halfWidth[p]
        if (d >= hw + r) return 0.0
        val lo = max(d - r, -hw); val hi = min(d + r, hw)
        return ((hi - lo) / (2 * r)).coerceIn(0.0, 1.0)
    }

    /** Distance from a point to piece p's centre line (round ends). */
    private fun distance(p: Int, x: Double, y: Double): Double {
        if (kind[p] == SEGMENT) {
            val dx = bx[p] - ax[p]; val dy = by[p] - ay[p]
            val len2 = dx * dx + dy * dy
            val t = if (len2 == 0.0) 0.0 else (((x - ax[p]) * dx + (y - ay[p]) * dy) / len2).coerceIn(0.0, 1.0)
            val px = ax[p] + t * dx - x; val py = ay[p] + t * dy - y
            return sqrt(px * px + py * py)
        }
        val rx = x - ax[p]; val ry = y - ay[p]
        val rho = sqrt(rx * rx + ry * ry)
        val sw = sweep[p]
        if (kotlin.math.abs(sw) >= 2 * PI) return kotlin.math.abs(rho - radius[p])
        var rel = atan2(ry, rx) - start[p]
        if (sw >= 0) { rel = mod2pi(rel); if (rel <= sw) return kotlin.math.abs(rho - radius[p]) }
        else { rel = -mod2pi(-rel); if (rel >= sw) return kotlin.math.abs(rho - radius[p]) }
        // Outside the sweep: distance to the nearer end point.
        val r = radius[p]
        val e0x = ax[p] + r * cos(start[p]); val e0y = ay[p] + r * sin(start[p])
        val e1x = ax[p] + r * cos(start[p] + sw); val e1y = ay[p] + r * sin(start[p] + sw)
        return min(hypot(x - e0x, y - e0y), hypot(x - e1x, y - e1y))
    }

    private class Piece(
        val kind: Int, val ax: Double, val ay: Double, val bx: Double, val by: Double,
        val r: Double, val start: Double, val sweep: Double, val hw: Double, val colour: TapeColour,
    )

    private companion object {
        const val SEGMENT = 0
        const val ARC = 1
        const val CELL_M = 0.02
        const val MAX_SPOT_RADIUS_M = 0.003
        val EMPTY = IntArray(0)

        fun mod2pi(a: Double): Double { val t = a % (2 * PI); return if (t < 0) t + 2 * PI else t }
    }
}

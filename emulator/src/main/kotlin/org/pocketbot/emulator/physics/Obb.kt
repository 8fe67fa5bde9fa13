package org.pocketbot.emulator.physics

import kotlin.math.abs
import kotlin.math.cos
import kotlin.math.sin

/** An oriented box (centre, heading, half extents) with a separating-axis overlap test. Mutable, for reuse. */
public class Obb {
    public var cx: Double = 0.0; public var cy: Double = 0.0
    public var ux: Double = 1.0; public var uy: Double = 0.0
    public var hx: Double = 0.0; public var hy: Double = 0.0

    public fun set(x: Double, y: Double, angleRad: Double, halfX: Double, halfY: Double): Obb {
        cx = x; cy = y; ux = cos(angleRad); uy = sin(angleRad); hx = halfX; hy = halfY
        return this
    }

    /** True when [p] is inside. */
    public fun contains(px: Double, py: Double): Boolean {
        val dx = px - cx; val dy = py - cy
        return abs(dx * ux + dy * uy) <= hx && abs(-dx * uy + dy * ux) <= hy
    }

    /**
     * Overlap of this box with [other]: false when they are apart; else true with the smallest push that
     * separates them, as depth and unit normal (pointing from [other] towards this box), in [out] (depth, nx, ny).
     */
    public fun overlap(other: Obb, out: DoubleArray): Boolean {
        var best = Double.MAX_VALUE
        var bnx = 0.0; var bny = 0.0
        val dx = cx - other.cx; val dy = cy - other.cy
        for (axis in 0 until 4) {
            val nx: Double; val ny: Double
            when (axis) {
                0 -> { nx = ux; ny = uy }
                1 -> { nx = -uy; ny = ux }
                2 -> { nx = other.ux; ny = other.uy }
                else -> { nx = -other.uy; ny = other.ux }
            }
            val ra = hx * abs(ux * nx + uy * ny) + hy * abs(-uy * nx + ux * ny)
            val rb = other.hx * abs(other.ux * nx + other.uy * ny) + other.hy * abs(-other.uy * nx + other.ux * ny)
            val d = dx * nx + dy * ny
            val o = ra + rb - abs(d)
            if (o <= 0) return false
            if (o < best) { best = o; if (d >= 0) { bnx = nx; bny = ny } else { bnx = -nx; bny = -ny } }
        }
        out[0] = best; out[1] = bnx; out[2] = bny
        return true
    }

    /**
     * Distance along the ray from (px, py) in direction (dx, dy) (unit) to this box, or +inf when it misses.
     * (Slab method in the box's frame.)
     */
    public fun rayDistance(px: Double, py: Double, dx: Double, dy: Double): Double {
        val rx = px - cx; val ry = py - cy
        val ox = rx * ux + ry * uy; val oy = -rx * uy + ry * ux
        val vx = dx * ux + dy * uy; val vy = -dx * uy + dy * ux
        var tMin = 0.0; var tMax = Double.MAX_VALUE
        for (k in 0..1) {
            val o = if (k == 0) ox else oy
            val v = if (k == 0) vx else vy
            val h = if (k == 0) hx else hy
            if (abs(v) < 1e-12) {
                if (abs(o) > h) return Double.POSITIVE_INFINITY
            } else {
                var t1 = (-h - o) / v; var t2 = (h - o) / v
                if (t1 > t2) { val t = t1; t1 = t2; t2 = t }
                if (t1 > tMin) tMin = t1
                if (t2 < tMax) tMax = t2
                if (tMin > tMax) return Double.POSITIVE_INFINITY
            }
        }
        return tMin
    }
}

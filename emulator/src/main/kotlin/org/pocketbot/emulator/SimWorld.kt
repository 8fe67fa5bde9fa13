package org.pocketbot.emulator

import org.pocketbot.emulator.physics.Obb
import org.pocketbot.emulator.physics.RobotParams
import org.pocketbot.emulator.world.Box
import org.pocketbot.emulator.world.Surface
import org.pocketbot.emulator.world.World
import org.pocketbot.sdk.Pose
import kotlin.math.PI
import kotlin.math.abs
import kotlin.math.ceil
import kotlin.math.cos
import kotlin.math.hypot
import kotlin.math.max
import kotlin.math.min
import kotlin.math.sin
import kotlin.math.sqrt

/** A box as it moves during the run. */
internal class SimBox(val spec: Box) {
    var x = spec.center.x
    var y = spec.center.y
    val angle = Math.toRadians(spec.angleDeg)
    val obb = Obb().set(x, y, angle, spec.widthM / 2, spec.heightM / 2)
    fun moveBy(dx: Double, dy: Double) { x += dx; y += dy; obb.set(x, y, angle, spec.widthM / 2, spec.heightM / 2) }
}

/**
 * The simulated world: floor, boxes and robots, and the interactions between robots that must happen at step
 * boundaries (IR messages, pushing boxes) so that stepping the robots in parallel stays deterministic.
 */
internal class SimWorld(val spec: World) {
    val surface = Surface(spec)
    val ambientAdc = spec.ambientAdc
    val boxes = spec.boxes.map { SimBox(it) }
    val robots = ArrayList<SimRobot>()

    // ---- placing robots ---------------------------------------------------------------------------------------

    /**
     * Where a new robot with [params] stands: the first of the world's start poses that is free, else the first free
     * spot of a grid over the floor that is off the tape (heading +x), bottom row first; null when none is free.
     * Free means that the robot's body, with [PLACE_CLEARANCE_M] all round, touches no robot and no box.
     */
    fun freePlace(params: RobotParams): Pose? {
        val body = Obb()
        val other = Obb()
        val out = DoubleArray(3)
        fun free(p: Pose): Boolean {
            body.set(p.xM, p.yM, p.headingRad, params.lengthM / 2 + PLACE_CLEARANCE_M, params.widthM / 2 + PLACE_CLEARANCE_M)
            return robots.none { it.body(other); body.overlap(other, out) } && boxes.none { body.overlap(it.obb, out) }
        }
        spec.starts.asSequence().map { it.toPose() }.firstOrNull(::free)?.let { return it }
        val pitch = hypot(params.lengthM, params.widthM) + 2 * PLACE_CLEARANCE_M
        val halfDiagonal = hypot(params.lengthM, params.widthM) / 2
        val cols = (spec.widthM / pitch).toInt()
        val rows = (spec.heightM / pitch).toInt()
        for (row in 0 until rows) for (col in 0 until cols) {
            val p = Pose((col + 0.5) * pitch, (row + 0.5) * pitch, 0.0)
            if (surface.distanceToTapeEdge(p.xM, p.yM) > halfDiagonal && free(p)) return p
        }
        return null
    }

    // ---- contacts -------------------------------------------------------------------------------------------

    private val contactMargin = 0.0002

    private companion object {
        /** Added to every reach that [markAlone] works out, against rounding. */
        const val SAFETY_M = 0.005
    }

    /** After a robot moved: pushes it out of any box it entered and notes the box it is pushing. Robot's own thread. */
    fun checkContacts(r: SimRobot) {
        r.contactBox = -1
        if (boxes.isEmpty()) return
        val body = r.scratchObb
        val out = r.scratchOverlap
        for (i in boxes.indices) {
            val b = boxes[i]
            val reach = r.params.lengthM + max(b.spec.widthM, b.spec.heightM)
            if (abs(r.x - b.x) > reach || abs(r.y - b.y) > reach) continue
            body.set(r.x, r.y, r.theta, r.params.lengthM / 2 + contactMargin, r.params.widthM / 2 + contactMargin)
            if (!body.overlap(b.obb, out)) continue
            val depth = out[0] - contactMargin
            val nx = out[1]; val ny = out[2]
            if (depth > 0) { r.x += nx * depth; r.y += ny * depth }
            // Pushing when the box is ahead: the separating normal points backwards along the heading.
            if (nx * cos(r.theta) + ny * sin(r.theta) < -0.5) { r.contactBox = i; r.pushDirX = -nx; r.pushDirY = -ny }
        }
    }

    /**
     * Robots that were pushing a box at the end of the last step: the box slides when their motors overcome its
     * friction (quasi-static: the box has no momentum), and the robots cannot go faster than the box.
     */
    fun resolvePushes(pushers: List<SimRobot>) {
        for (bi in boxes.indices) {
            var sumForce = 0.0; var sumSlope = 0.0; var dirX = 0.0; var dirY = 0.0; var fastest = 0.0; var count = 0
            for (r in pushers) {
                if (r.contactBox != bi) continue
                val c = r.pushDirX * cos(r.theta) + r.pushDirY * sin(r.theta)
                val stall = r.params.stallForcePerWheelN * r.batteryLoadedV() / r.params.nominalBatteryV
                // Force along the push direction at box speed u: c * (driveForce - 2 * stall * u / v0).
                sumForce += c * r.driveForceN()
                sumSlope += c * 2 * stall / r.params.noLoadSpeedMps
                dirX += r.pushDirX; dirY += r.pushDirY
                fastest = max(fastest, r.forwardSpeed * c)
                count++
            }
            if (count == 0) continue
            val box = boxes[bi]
            val friction = if (box.spec.movable) box.spec.friction * box.spec.massKg * SimRobot.G else Double.MAX_VALUE
            var u = if (sumSlope > 0 && sumForce > friction) (sumForce - friction) / sumSlope else 0.0
            u = min(u, fastest).coerceAtLeast(0.0)
            val norm = hypot(dirX, dirY)
            if (u > 0 && norm > 0) {
                val d = u * SimTime.STEP_S
                box.moveBy(dirX / norm * d, dirY / norm * d)
            }
            for (r in pushers) {
                if (r.contactBox != bi) continue
                val c = r.pushDirX * cos(r.theta) + r.pushDirY * sin(r.theta)
                r.limitForwardSpeed(if (c > 1e-6) u / c else 0.0)
            }
        }
    }

    // ---- IR -------------------------------------------------------------------------------------------------

    private var gridCols = 1
    private var gridRows = 1
    private val gridCell = 0.16
    private var cellHead = IntArray(1)
    private var next = IntArray(0)
    // Robot positions at the step's end (kept up to date by separateRobots' shoves), flat for the serial part.
    private var posX = DoubleArray(0)
    private var posY = DoubleArray(0)

    private fun buildGrid() {
        gridCols = max(1, ceil(spec.widthM / gridCell).toInt())
        gridRows = max(1, ceil(spec.heightM / gridCell).toInt())
        if (cellHead.size != gridCols * gridRows) cellHead = IntArray(gridCols * gridRows)
        cellHead.fill(-1)
        if (next.size < robots.size) { next = IntArray(robots.size); posX = DoubleArray(robots.size); posY = DoubleArray(robots.size) }
        for (i in robots.indices) {
            val r = robots[i]
            val x = r.x; val y = r.y
            posX[i] = x; posY[i] = y
            val c = cellOf(x, y)
            next[i] = cellHead[c]; cellHead[c] = i
        }
    }

    private fun cellOf(x: Double, y: Double): Int {
        val cx = (x / gridCell).toInt().coerceIn(0, gridCols - 1)
        val cy = (y / gridCell).toInt().coerceIn(0, gridRows - 1)
        return cy * gridCols + cx
    }

    /** Everything between robots at the end of a step, in a fixed order: IR first, then collisions. */
    fun afterStep() {
        if (robots.isEmpty()) return
        buildGrid()
        exchangeIr()
        separateRobots()
    }

    /** Delivers every IR message sent in this step to the receivers that see it, and reflections to their senders. */
    fun exchangeIr() {
        var any = false
        for (r in robots) if (r.irOutCount > 0) { any = true; break }
        if (!any) return
        val ledHalf = Math.toRadians(robots[0].params.irLedHalfAngleDeg)
        val cosLed = cos(ledHalf)
        for (s in robots) {
            if (s.irOutCount == 0) continue
            val p = s.params
            for (k in 0 until s.irOutCount) {
                val led = s.irOutLed[k]
                val power = s.irOutPower[k]
                if (power <= 0) continue
                val range = p.irRangeM * power / 100.0
                // LED position and direction.
                // LED position (lx, ly) and direction (la) in the robot frame; no tuple: this runs per beacon.
                val lx = when (led) { 0 -> p.lengthM / 2; 2 -> -p.lengthM / 2; else -> 0.0 }
                val ly = when (led) { 1 -> -p.widthM / 2; 3 -> p.widthM / 2; else -> 0.0 }
                val la = when (led) { 0 -> 0.0; 1 -> -PI / 2; 2 -> PI; else -> PI / 2 }
                val c = cos(s.theta); val sn = sin(s.theta)
                val ex = s.x + lx * c - ly * sn; val ey = s.y + lx * sn + ly * c
                val dirA = s.theta + la
                val dx = cos(dirA); val dy = sin(dirA)
                // Other robots.
                val span = (range / gridCell).toInt() + 1
                forEachRobotNear(ex, ey, span) { q -> if (q !== s) deliverTo(q, s, k, ex, ey, dx, dy, range, cosLed, span) }
                // Reflection from boxes, back into the sender's receiver on that side.
                if (led == 0 || led == 2) {
                    val reflectRange = range / 2
                    var hit = false
                    for (b in boxes) {
                        if (hypot(b.x - ex, b.y - ey) > reflectRange + b.spec.widthM + b.spec.heightM) continue
                        for (ray in -1..1) {
                            val a = dirA + ray * ledHalf
                            if (b.obb.rayDistance(ex, ey, cos(a), sin(a)) <= reflectRange) { hit = true; break }
                        }
                        if (hit) break
                    }
                    if (hit) s.irHeard(if (led == 0) 0 else 1, s.irOutSender[k], led, power, s.irOutLen[k], s.irOutLo[k], s.irOutHi[k])
                }
            }
            s.irOutCount = 0
        }
    }

    private fun deliverTo(q: SimRobot, s: SimRobot, k: Int, ex: Double, ey: Double, dx: Double, dy: Double, range: Double, cosLed: Double, span: Int) {
        val qp = q.params
        val c = cos(q.theta); val sn = sin(q.theta)
        for (side in 0..1) {
            val off = if (side == 0) qp.lengthM / 2 else -qp.lengthM / 2
            val rx = q.x + off * c; val ry = q.y + off * sn
            val vx = rx - ex; val vy = ry - ey
            val dist = sqrt(vx * vx + vy * vy)
            if (dist > range || dist < 1e-9) continue
            if ((vx * dx + vy * dy) / dist < cosLed) continue // outside the LED's cone
            // Receiver axis: forward for the front one, backward for the rear one; the light comes in along -v.
            val ax = if (side == 0) c else -c; val ay = if (side == 0) sn else -sn
            val cosIn = (-vx * ax - vy * ay) / dist
            if (cosIn < cos(Math.toRadians(qp.irReceiverHalfAngleDeg))) continue
            if (blocked(ex, ey, rx, ry, dist, s, q, span)) continue
            q.irHeard(side, s.irOutSender[k], s.irOutLed[k], s.irOutPower[k], s.irOutLen[k], s.irOutLo[k], s.irOutHi[k])
        }
    }

    private val occluder = Obb()

    /**
     * Whether the light from (ex, ey) to a receiver at (rx, ry), [dist] away, is stopped on its way by a box or by
     * the body of a robot other than its sender [s] and receiver [q] (IR does not pass through bodies: a robot
     * hears the robot right in front of it, not the ones hidden behind that one).
     */
    private fun blocked(ex: Double, ey: Double, rx: Double, ry: Double, dist: Double, s: SimRobot, q: SimRobot, span: Int): Boolean {
        val ux = (rx - ex) / dist; val uy = (ry - ey) / dist
        for (b in boxes) {
            val reach = (b.spec.widthM + b.spec.heightM) / 2
            if (distanceToSegment(b.x, b.y, ex, ey, ux, uy, dist) > reach) continue
            if (b.obb.rayDistance(ex, ey, ux, uy) < dist) return true
        }
        val reach = robots[0].params.let { hypot(it.lengthM, it.widthM) / 2 }
        forEachRobotNear(ex, ey, span) { o ->
            if (o === s || o === q || distanceToSegment(o.x, o.y, ex, ey, ux, uy, dist) > reach) return@forEachRobotNear
            o.body(occluder)
            if (occluder.rayDistance(ex, ey, ux, uy) < dist) return true
        }
        return false
    }

    /** Calls [action] for each robot in the grid cells within [span] cells of the one holding (x, y), in grid order. */
    private inline fun forEachRobotNear(x: Double, y: Double, span: Int, action: (SimRobot) -> Unit) {
        val cx0 = (x / gridCell).toInt(); val cy0 = (y / gridCell).toInt()
        for (gy in max(0, cy0 - span)..min(gridRows - 1, cy0 + span)) for (gx in max(0, cx0 - span)..min(gridCols - 1, cx0 + span)) {
            var i = cellHead[gy * gridCols + gx]
            while (i >= 0) {
                val robot = robots[i]
                i = next[i]
                action(robot)
            }
        }
    }

    /** Distance from (px, py) to the segment from (ax, ay) along the unit vector (ux, uy) for [len]. */
    private fun distanceToSegment(px: Double, py: Double, ax: Double, ay: Double, ux: Double, uy: Double, len: Double): Double {
        val t = ((px - ax) * ux + (py - ay) * uy).coerceIn(0.0, len)
        return hypot(ax + ux * t - px, ay + uy * t - py)
    }

    // ---- robots out of everyone's reach ------------------------------------------------------------------------

    /**
     * Marks [SimRobot.alone] every robot that no other robot or box can affect, or be affected by, within the next
     * [ms] steps, whatever the robots do meanwhile; returns how many. Such a robot's IR reaches no receiver and no box
     * that reflects it, no other body is near enough to occlude IR, collide or push with it, and so what happens
     * between robots at the end of each of those steps leaves it untouched: it can run them in a row.
     *
     * The bounds: a robot's centre moves at most its wheels' top speed (no-load speed at a full battery) per second,
     * a box at most as fast as the robots pushing it; a robot's LEDs, receivers and body lie within half its diagonal
     * of its centre; IR carries at most [org.pocketbot.emulator.physics.RobotParams.irRangeM], a box reflects within
     * half that ([exchangeIr]) and a box touches a robot within [checkContacts]' reach.
     */
    fun markAlone(ms: Int): Int {
        if (robots.isEmpty()) return 0
        val p = robots[0].params
        val drift = ms * SimTime.STEP_S * p.noLoadSpeedMps * p.batteryFullV / p.nominalBatteryV
        val halfDiagonal = hypot(p.lengthM, p.widthM) / 2
        val robotReach = p.irRangeM + 2 * halfDiagonal + 2 * drift + SAFETY_M
        val robotReach2 = robotReach * robotReach
        buildGrid()
        val span = (robotReach / gridCell).toInt() + 1
        var count = 0
        for (i in robots.indices) {
            val r = robots[i]
            r.alone = false
            if (r.contactBox >= 0 || nearBox(r, halfDiagonal, drift)) continue
            val x = posX[i]; val y = posY[i]
            var near = false
            val cx0 = (x / gridCell).toInt().coerceIn(0, gridCols - 1)
            val cy0 = (y / gridCell).toInt().coerceIn(0, gridRows - 1)
            scan@ for (gy in max(0, cy0 - span)..min(gridRows - 1, cy0 + span)) for (gx in max(0, cx0 - span)..min(gridCols - 1, cx0 + span)) {
                var j = cellHead[gy * gridCols + gx]
                while (j >= 0) {
                    if (j != i) {
                        val dx = posX[j] - x; val dy = posY[j] - y
                        if (dx * dx + dy * dy <= robotReach2) { near = true; break@scan }
                    }
                    j = next[j]
                }
            }
            if (!near) { r.alone = true; count++ }
        }
        return count
    }

    private fun nearBox(r: SimRobot, halfDiagonal: Double, drift: Double): Boolean {
        for (b in boxes) {
            val reflect = halfDiagonal + r.params.irRangeM / 2 + b.spec.widthM + b.spec.heightM
            val contact = (r.params.lengthM + max(b.spec.widthM, b.spec.heightM)) * sqrt(2.0)
            if (hypot(r.x - b.x, r.y - b.y) <= max(reflect, contact) + 2 * drift + SAFETY_M) return true
        }
        return false
    }

    // ---- robots bumping into robots ----------------------------------------------------------------------------

    /** Pairs of robot bodies found overlapping (and pushed apart) at the end of a step, since the start. */
    var robotContacts = 0L; private set

    private val bodyA = Obb()
    private val bodyB = Obb()
    private val overlapOut = DoubleArray(3)

    /**
     * Separates robots whose bodies overlap, each moved back by half the overlap (a shove, not momentum); in
     * robot order, so the result is deterministic. Serial, at the step's end.
     */
    fun separateRobots() {
        if (robots.size < 2) return
        val reach = robots[0].params.lengthM * 1.2
        val px = posX; val py = posY
        for (ia in robots.indices) {
            val cx0 = (px[ia] / gridCell).toInt().coerceIn(0, gridCols - 1)
            val cy0 = (py[ia] / gridCell).toInt().coerceIn(0, gridRows - 1)
            for (gy in max(0, cy0 - 1)..min(gridRows - 1, cy0 + 1)) for (gx in max(0, cx0 - 1)..min(gridCols - 1, cx0 + 1)) {
                var ib = cellHead[gy * gridCols + gx]
                while (ib >= 0) {
                    val nb = next[ib]
                    if (ib > ia && abs(px[ia] - px[ib]) < reach && abs(py[ia] - py[ib]) < reach) {
                        val a = robots[ia]; val b = robots[ib]
                        a.body(bodyA); b.body(bodyB)
                        if (bodyA.overlap(bodyB, overlapOut)) {
                            robotContacts++
                            val d = overlapOut[0] / 2
                            a.shove(overlapOut[1] * d, overlapOut[2] * d)
                            b.shove(-overlapOut[1] * d, -overlapOut[2] * d)
                            px[ia] = a.x; py[ia] = a.y; px[ib] = b.x; py[ib] = b.y
                        }
                    }
                    ib = nb
                }
            }
        }
    }
}

/** Room left between a newly placed robot and any robot or box already there. */
private const val PLACE_CLEARANCE_M: Double = 0.01

package org.pocketbot.sdk

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.atomicfu.locks.SynchronizedObject
import kotlinx.atomicfu.locks.synchronized

/** One point of a [Trajectory]: where the robot was at robot time [timeMs]. */
public class TrajectoryPoint(public val timeMs: Long, public val pose: Pose) {
    override fun equals(other: Any?): Boolean = other is TrajectoryPoint && timeMs == other.timeMs && pose == other.pose
    override fun hashCode(): Int = timeMs.hashCode() * 31 + pose.hashCode()
    override fun toString(): String = "$timeMs ms: $pose"
}

/** A [Trajectory] as those who read it see it: its points and length, no way to add to it. */
public interface ReadOnlyTrajectory {
    /** The points so far, oldest first. */
    public val points: StateFlow<List<TrajectoryPoint>>

    /** Length of the path so far, in metres (of the points kept). */
    public val lengthM: Double

    /** The points as CSV: `time_ms,x_m,y_m,heading_rad`, one line per point after a header. */
    public fun toCsv(): String
}

/**
 * A path as a list of timed poses, for drawing and export: [Odometry.trajectory] is a robot's dead-reckoned path
 * (read-only: odometry records it); a face may keep another one (the emulator's ground truth, say) and [add] to it.
 *
 * A point is kept when the robot moved at least [minStepM] or turned at least [minTurnRad] since the last kept one,
 * so a robot standing still adds nothing. When [capacity] points are kept, every second point is dropped (the path
 * keeps its shape at half the resolution), so a long run never grows without bound. [points] is a snapshot that
 * never changes once handed out; adding is cheap (no copy of the path per point). Safe to use from any thread.
 */
public class Trajectory(
    public val capacity: Int = 20_000,
    public val minStepM: Double = 0.001,
    public val minTurnRad: Double = 0.02,
) : ReadOnlyTrajectory {
    init {
        require(capacity >= 2) { "capacity must be at least 2" }
    }

    private val lock = SynchronizedObject()

    private var array = arrayOfNulls<TrajectoryPoint>(16)
    private var size = 0
    private var length = 0.0
    private val _points = MutableStateFlow<List<TrajectoryPoint>>(emptyList())

    override val points: StateFlow<List<TrajectoryPoint>> = _points.asStateFlow()

    override val lengthM: Double get() = length

    /** Adds the pose at robot time [timeMs], unless the robot has not moved enough since the last point. */
    public fun add(timeMs: Long, pose: Pose): Unit = synchronized(lock) { append(TrajectoryPoint(timeMs, pose)) }

    /** Forgets every point. */
    public fun clear(): Unit = synchronized(lock) {
        array = arrayOfNulls(16)
        size = 0
        length = 0.0
        _points.value = emptyList()
    }

    override fun toCsv(): String = buildString {
        append("time_ms,x_m,y_m,heading_rad\n")
        for (p in _points.value) append("${p.timeMs},${p.pose.xM},${p.pose.yM},${p.pose.headingRad}\n")
    }

    private fun append(p: TrajectoryPoint) {
        val last = if (size > 0) array[size - 1] else null
        if (last != null) {
            val step = last.pose.distanceTo(p.pose)
            if (step < minStepM && kotlin.math.abs(wrapAngle(p.pose.headingRad - last.pose.headingRad)) < minTurnRad) return
            length += step
        }
        if (size == capacity) halve()
        if (size == array.size) array = array.copyOf(minOf(capacity, array.size * 2))
        array[size++] = p
        _points.value = Snapshot(array, size)
    }

    /** Keeps every second point (and always the newest): a new array, so snapshots handed out stay as they were. */
    private fun halve() {
        val kept = arrayOfNulls<TrajectoryPoint>(array.size)
        var n = 0
        for (i in 0 until size step 2) kept[n++] = array[i]
        if ((size - 1) % 2 != 0) kept[n++] = array[size - 1]
        array = kept
        size = n
    }

    /** The first [size] points of [array]: appends only write beyond them, so this view never changes. */
    private class Snapshot(private val array: Array<TrajectoryPoint?>, override val size: Int) : AbstractList<TrajectoryPoint>() {
        override fun get(index: Int): TrajectoryPoint {
            if (index !in 0 until size) throw IndexOutOfBoundsException("index $index, size $size")
            return array[index]!!
        }
    }
}

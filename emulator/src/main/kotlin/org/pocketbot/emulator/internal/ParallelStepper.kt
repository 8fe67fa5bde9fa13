package org.pocketbot.emulator.internal

import java.util.concurrent.atomic.AtomicInteger
import java.util.concurrent.atomic.AtomicIntegerArray
import java.util.concurrent.locks.LockSupport

/**
 * Runs `task(i)` for i in 0 until n on up to [threads] threads (the caller's included) and returns when all are
 * done. Made for many tiny tasks per simulated millisecond.
 *
 * The indices are split into one contiguous part per thread, so a robot is normally stepped by the same thread
 * (its data stays in that core's cache); a thread that finishes its part takes small blocks from the others,
 * and the caller never waits for a worker that has not started: on a busy machine a descheduled worker costs
 * nothing, its part is simply done by the others. Which thread ran which index must not matter to the result.
 */
internal class ParallelStepper(val threads: Int) : AutoCloseable {
    /** The work for index i; not a (Int) -> Unit, whose calls box every index above 127. */
    fun interface Task {
        fun run(i: Int)
    }

    private val workers = ArrayList<Thread>()
    @Volatile private var closed = false

    /** One round of work; published in [job], the workers notice the new round number. */
    private class Job(val round: Long, val task: Task, count: Int, val block: Int, parts: Int) {
        val starts = IntArray(parts + 1) { (it.toLong() * count / parts).toInt() }
        val next = AtomicIntegerArray(parts)
    }

    @Volatile private var job: Job? = null
    private val active = AtomicInteger()
    @Volatile private var failure: Throwable? = null
    private var round = 0L

    init {
        for (w in 1 until threads) {
            workers += Thread({ workerLoop(w) }, "emulator-step-$w").apply { isDaemon = true; start() }
        }
    }

    fun run(n: Int, task: Task) {
        if (threads <= 1 || n < 2) { for (i in 0 until n) task.run(i); return }
        round++
        val j = Job(round, task, n, (n / (threads * 8)).coerceIn(1, MAX_BLOCK), threads)
        job = j
        for (w in workers) LockSupport.unpark(w)
        work(j, 0)
        var spins = 0
        while (active.get() > 0) {
            if (++spins < SPINS) Thread.onSpinWait() else Thread.yield()
        }
        job = null
        failure?.let { failure = null; throw IllegalStateException("a robot's step failed", it) }
    }

    /** Runs the blocks of part [home], then helps with the other parts until nothing is left. */
    private fun work(j: Job, home: Int) {
        val parts = j.starts.size - 1
        for (k in 0 until parts) {
            val p = (home + k) % parts
            val base = j.starts[p]
            val end = j.starts[p + 1]
            while (true) {
                val start = base + j.next.getAndAdd(p, j.block)
                if (start >= end) break
                val stop = minOf(end, start + j.block)
                for (i in start until stop) j.task.run(i)
                if (DEBUG) done.addAndGet(home, stop - start)
            }
        }
    }

    private fun workerLoop(home: Int) {
        var seen = 0L
        while (!closed) {
            var spins = 0
            while (!closed && (job?.round ?: seen) == seen) {
                // Parked until the next round's unpark (or close): an idle or paused emulator's workers take no CPU.
                if (++spins < SPINS) Thread.onSpinWait() else LockSupport.park(this)
            }
            if (closed) return
            active.incrementAndGet()
            try {
                // Re-read after announcing ourselves: the caller waits for us only from here on.
                val j = job
                if (j != null && j.round != seen) {
                    seen = j.round
                    work(j, home)
                }
            } catch (t: Throwable) {
                failure = t
            } finally {
                active.decrementAndGet()
            }
        }
    }

    override fun close() {
        closed = true
        for (w in workers) LockSupport.unpark(w)
    }

    private val done = AtomicIntegerArray(threads)

    /** For diagnosis (-Dpocketbot.emulator.debugModes=true): tasks run by each thread since the last call. */
    fun takeCounts(): String = (0 until threads).joinToString("/") { done.getAndSet(it, 0).toString() }

    private companion object {
        val DEBUG = System.getProperty("pocketbot.emulator.debugModes") == "true"
        const val MAX_BLOCK = 8
        const val SPINS = 4_000
    }
}

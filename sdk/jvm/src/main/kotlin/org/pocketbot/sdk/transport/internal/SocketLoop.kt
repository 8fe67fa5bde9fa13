package org.pocketbot.sdk.transport.internal

import kotlinx.coroutines.CancellableContinuation
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.Delay
import kotlinx.coroutines.DisposableHandle
import kotlinx.coroutines.ExperimentalCoroutinesApi
import kotlinx.coroutines.InternalCoroutinesApi
import kotlinx.coroutines.suspendCancellableCoroutine
import java.io.IOException
import java.nio.channels.ClosedChannelException
import java.nio.channels.SelectionKey
import java.nio.channels.Selector
import java.nio.channels.SocketChannel
import java.util.PriorityQueue
import java.util.concurrent.ConcurrentLinkedQueue
import kotlin.coroutines.CoroutineContext
import kotlin.coroutines.resume

/**
 * An event loop for TCP sockets: one thread that waits on its sockets (non-blocking NIO), resumes the coroutine
 * waiting on a socket the moment it can read, write or finish connecting, and is itself a [CoroutineDispatcher] with
 * its own timers. The process has a few loops ([next] hands them out in turn).
 *
 * A TCP robot's link runs on its socket's loop too (see [org.pocketbot.sdk.transport.RobotDevice.eventLoop]): the
 * socket reader (in `Dispatchers.Unconfined`) reads and decodes on the loop, and the link takes the frame, updates
 * the robot's state and emits it on the same thread. A host mirroring hundreds of robots then pays no thread
 * hand-over per frame: waking a parked worker thread for every frame cost more CPU than everything else on the path.
 */
@OptIn(InternalCoroutinesApi::class, ExperimentalCoroutinesApi::class)
internal class SocketLoop private constructor(private val name: String) : CoroutineDispatcher(), Delay {
    private val selector: Selector = Selector.open()
    private val requests = ConcurrentLinkedQueue<Request>()
    private val tasks = ConcurrentLinkedQueue<Runnable>()
    /** Touched on the loop thread only; other threads add timers through [tasks]. */
    private val timers = PriorityQueue<Timer>()
    private var timerCount = 0L

    private class Request(val channel: SocketChannel, val ops: Int, val continuation: CancellableContinuation<Unit>)

    /** What waits on one socket: at most one reader, one writer or connector at a time. */
    private class Waiters {
        var read: CancellableContinuation<Unit>? = null
        var write: CancellableContinuation<Unit>? = null
    }

    private class Timer(val dueNanos: Long, val block: Runnable) : Comparable<Timer>, DisposableHandle {
        @Volatile var cancelled = false
        /** Order of scheduling, for timers due at the same nanosecond; set on the loop. */
        var order = 0L

        override fun compareTo(other: Timer): Int =
            if (dueNanos != other.dueNanos) (dueNanos - other.dueNanos).compareTo(0) else order.compareTo(other.order)

        override fun dispose() {
            cancelled = true // left in the heap until due: cheaper than a removal from another thread
        }
    }

    private val thread = Thread(::loop, name).apply { isDaemon = true; start() }

    private val onLoop: Boolean get() = Thread.currentThread() === thread

    /**
     * Suspends until [channel] is ready for [ops] (OP_READ, OP_WRITE or OP_CONNECT); throws when it closed.
     * A reader resumed on the loop that waits again registers at once, without waking the selector: that is the
     * common case of a busy socket, and it costs no system call.
     */
    suspend fun await(channel: SocketChannel, ops: Int) {
        suspendCancellableCoroutine { c ->
            if (onLoop) {
                register(Request(channel, ops, c))
            } else {
                requests += Request(channel, ops, c)
                selector.wakeup()
            }
        }
    }

    // ---- the dispatcher ----

    override fun dispatch(context: CoroutineContext, block: Runnable) {
        tasks += block
        if (!onLoop) selector.wakeup()
    }

    override fun scheduleResumeAfterDelay(timeMillis: Long, continuation: CancellableContinuation<Unit>) {
        val timer = schedule(timeMillis) { with(continuation) { resumeUndispatched(Unit) } }
        continuation.invokeOnCancellation { timer.dispose() }
    }

    override fun invokeOnTimeout(timeMillis: Long, block: Runnable, context: CoroutineContext): DisposableHandle =
        schedule(timeMillis, block)

    private fun schedule(timeMillis: Long, block: Runnable): Timer {
        val due = System.nanoTime() + timeMillis.coerceIn(0, Long.MAX_VALUE / 2_000_000) * 1_000_000
        val timer = Timer(due, block)
        if (onLoop) addTimer(timer) else dispatch(kotlin.coroutines.EmptyCoroutineContext, Runnable { addTimer(timer) })
        return timer
    }

    private fun addTimer(t: Timer) {
        t.order = timerCount++
        timers += t
    }

    override fun toString(): String = name

    // ---- the loop ----

    private fun loop() {
        while (true) {
            try {
                while (true) register(requests.poll() ?: break)
                val wait = waitMillis()
                when {
                    wait < 0 -> selector.selectNow()
                    else -> selector.select(wait)
                }
                val keys = selector.selectedKeys().iterator()
                while (keys.hasNext()) {
                    val key = keys.next()
                    keys.remove()
                    try {
                        ready(key)
                    } catch (e: java.nio.channels.CancelledKeyException) {
                        closed(key) // its socket was closed from another thread after the select
                    }
                }
                runDueTimers()
                runTasks()
            } catch (e: IOException) {
                // A select that failed on one socket: the others go on, the next round sees the closed one.
            }
        }
    }

    /** -1: work is waiting (do not block); 0: nothing scheduled (block until woken); else ms to the next timer. */
    private fun waitMillis(): Long {
        if (tasks.isNotEmpty() || requests.isNotEmpty()) return -1
        val next = timers.peek() ?: return 0
        val nanos = next.dueNanos - System.nanoTime()
        return if (nanos <= 0) -1 else (nanos + 999_999) / 1_000_000
    }

    private fun runDueTimers() {
        val now = System.nanoTime()
        while (true) {
            val t = timers.peek() ?: return
            if (t.dueNanos - now > 0) return
            timers.poll()
            if (!t.cancelled) runSafely(t.block)
        }
    }

    /** Runs the tasks queued so far; tasks they queue wait for the next round, after the sockets had their turn. */
    private fun runTasks() {
        repeat(tasks.size) { runSafely(tasks.poll() ?: return) }
    }

    private fun runSafely(task: Runnable) {
        try {
            task.run()
        } catch (e: Throwable) {
            // A coroutine task handles its own failures; anything else must not stop every socket of the process.
            Thread.currentThread().uncaughtExceptionHandler?.uncaughtException(Thread.currentThread(), e)
        }
    }

    private fun register(r: Request) {
        val key = try {
            r.channel.keyFor(selector) ?: r.channel.register(selector, 0, Waiters())
        } catch (e: ClosedChannelException) {
            r.continuation.resumeWith(Result.failure(e))
            return
        }
        val waiters = key.attachment() as Waiters
        try {
            key.interestOps(key.interestOps() or r.ops)
        } catch (e: java.nio.channels.CancelledKeyException) {
            r.continuation.resumeWith(Result.failure(ClosedChannelException()))
            return
        }
        if (r.ops == SelectionKey.OP_READ) waiters.read = r.continuation else waiters.write = r.continuation
    }

    /** The socket of [key] is closed: whoever waits on it learns so. */
    private fun closed(key: SelectionKey) {
        val waiters = key.attachment() as Waiters
        val reader = waiters.read
        val writer = waiters.write
        waiters.read = null
        waiters.write = null
        reader?.resumeWith(Result.failure(ClosedChannelException()))
        writer?.resumeWith(Result.failure(ClosedChannelException()))
    }

    private fun ready(key: SelectionKey) {
        val waiters = key.attachment() as Waiters
        if (!key.isValid) return closed(key)
        val ready = key.readyOps()
        var interest = key.interestOps()
        if (ready and SelectionKey.OP_READ != 0) {
            val reader = waiters.read
            if (reader != null) {
                // The read interest stays on while a reader comes back for more (the usual case): no epoll_ctl
                // per frame. Readiness is level-triggered, so a reader that waits again is woken by the next data.
                waiters.read = null
                reader.resume(Unit)
            } else {
                // Nobody reads (the reader is held up downstream): stop reporting until it waits again.
                interest = interest and SelectionKey.OP_READ.inv()
                if (key.isValid) key.interestOps(interest)
            }
        }
        if (ready and (SelectionKey.OP_WRITE or SelectionKey.OP_CONNECT) != 0 && key.isValid) {
            interest = key.interestOps() and (SelectionKey.OP_WRITE or SelectionKey.OP_CONNECT).inv()
            waiters.write?.let { waiters.write = null; key.interestOps(interest); it.resume(Unit) }
        }
    }

    companion object {
        /**
         * One loop per four cores (at least one; `-Dpocketbot.tcp.loops=N` sets it): one busy loop costs less CPU
         * per frame than several half-idle ones, and one carries about a hundred thousand frames a second.
         */
        private val loops = List(
            (System.getProperty("pocketbot.tcp.loops")?.toIntOrNull() ?: (Runtime.getRuntime().availableProcessors() / 4)).coerceIn(1, 8),
        ) { SocketLoop("pocketbot-sockets-$it") }
        private val turn = java.util.concurrent.atomic.AtomicInteger()

        /** The loop for a new robot: in turn, so a fleet's sockets spread over the cores. */
        fun next(): SocketLoop = loops[Math.floorMod(turn.getAndIncrement(), loops.size)]
    }
}

package org.pocketbot.sdk.transport.internal

import kotlinx.coroutines.CancellableContinuation
import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.suspendCancellableCoroutine
import java.io.IOException
import java.nio.channels.ClosedChannelException
import java.nio.channels.SelectionKey
import java.nio.channels.Selector
import java.nio.channels.SocketChannel
import java.util.concurrent.ConcurrentLinkedQueue
import kotlin.coroutines.CoroutineContext
import kotlin.coroutines.resume

/**
 * An event loop for TCP sockets: one thread that waits on its sockets (non-blocking NIO), resumes the coroutine
 * waiting on a socket the moment it can read, write or finish connecting, and is itself a [CoroutineDispatcher]. The
 * process has a few loops ([next] hands them out in turn).
 *
 * A TCP robot's link runs on its socket's loop too (see [org.pocketbot.sdk.transport.RobotDevice.eventLoop]): the
 * socket reader (in `Dispatchers.Unconfined`) reads and decodes on the loop, and the link takes the frame, updates
 * the robot's state and emits it on the same thread. A host mirroring hundreds of robots then pays no thread
 * hand-over per frame: waking a parked worker thread for every frame cost more CPU than everything else on the path.
 * Like `Dispatchers.Main.immediate`, a coroutine resumed on the loop's own thread runs at once (kotlinx.coroutines
 * queues nested resumptions on the thread, so stacks do not grow): the frame a reader hands over is handled before
 * the loop looks at the next socket, without a round through the task queue.
 *
 * Only public kotlinx.coroutines API: the loop has no timers of its own (that would mean implementing the internal
 * `Delay`), so a `delay` of a coroutine on the loop (the link's heartbeat, timeouts) waits on kotlinx.coroutines'
 * default timer thread, which dispatches its resumption back here. That is a few wakes per robot and second against
 * the hundred frames each robot sends.
 */
internal class SocketLoop private constructor(private val name: String) : CoroutineDispatcher() {
    private val selector: Selector = Selector.open()
    private val requests = ConcurrentLinkedQueue<Request>()
    private val tasks = ConcurrentLinkedQueue<Runnable>()

    private class Request(val channel: SocketChannel, val ops: Int, val continuation: CancellableContinuation<Unit>)

    /** What waits on one socket: at most one reader, one writer or connector at a time. */
    private class Waiters {
        var read: CancellableContinuation<Unit>? = null
        var write: CancellableContinuation<Unit>? = null
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

    /** A coroutine resumed on the loop's thread runs at once; from any other thread it is queued here. */
    override fun isDispatchNeeded(context: CoroutineContext): Boolean = !onLoop

    override fun dispatch(context: CoroutineContext, block: Runnable) {
        tasks += block
        if (!onLoop) selector.wakeup()
    }

    override fun toString(): String = name

    // ---- the loop ----

    private fun loop() {
        while (true) {
            try {
                while (true) register(requests.poll() ?: break)
                if (tasks.isNotEmpty() || requests.isNotEmpty()) selector.selectNow() else selector.select()
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
                runTasks()
            } catch (e: IOException) {
                // A select that failed on one socket: the others go on, the next round sees the closed one.
            }
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

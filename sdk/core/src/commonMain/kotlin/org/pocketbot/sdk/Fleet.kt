package org.pocketbot.sdk

import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.NonCancellable
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.async
import kotlinx.coroutines.awaitAll
import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.take
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.RobotDevice
import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds

/**
 * Many robots under one scope (thesis 5: "handle simultaneous connections to many robots"): discover and connect
 * them in parallel, start movements on several at the same moment (thesis A.2), close them all.
 *
 * ```
 * runBlocking {
 *     Fleet(this).use { fleet ->
 *         val (a, b) = fleet.discoverAndConnect(discoverer, count = 2)
 *         fleet.enqueueTogether(mapOf(a to Movement.Straight(0.05, 0.1), b to Movement.Straight(0.05, 0.1)))
 *         fleet.awaitIdle()
 *     }
 * }
 * ```
 * The fleet belongs to [scope] as each [Robot] does: it is a child [Job] of the scope, and its robots are children
 * of the fleet. Cancelling the scope closes every robot in it; the scope does not complete while the fleet is open:
 * [close] it (`use {}`) or [disconnect] it, and nothing the fleet started outlives the scope.
 *
 * @throws IllegalStateException when [scope] has ended already (cancelled or completed).
 */
public class Fleet(scope: CoroutineScope, private val options: RobotOptions) : AutoCloseable {
    /** A fleet whose robots connect with the default [RobotOptions]. */
    public constructor(scope: CoroutineScope) : this(scope, RobotOptions())

    private val job = SupervisorJob(scope.coroutineContext[Job])
    private val fleetScope = CoroutineScope(scope.coroutineContext + job)
    private val _robots = MutableStateFlow<List<Robot>>(emptyList())

    init {
        check(job.isActive) { "cannot make a Fleet: its scope has ended (${scope.coroutineContext[Job]})" }
    }

    /** The connected robots, in the order they joined. */
    public val robots: StateFlow<List<Robot>> = _robots.asStateFlow()

    /**
     * Connects [device] (see [RobotDevice.connect]) into this fleet.
     *
     * @throws IllegalStateException when the fleet is closed or its scope has ended.
     */
    public suspend fun connect(device: RobotDevice, options: RobotOptions = this.options): Robot {
        check(job.isActive) { "cannot connect ${device.name}: the fleet is closed or its scope has ended" }
        val robot = device.connect(fleetScope, options)
        _robots.update { it + robot }
        return robot
    }

    /**
     * Connects all [devices] in parallel; when one fails, or the caller is cancelled, it cancels the others, closes
     * those that did connect and throws (the cancellation propagates as such).
     */
    public suspend fun connectAll(devices: List<RobotDevice>): List<Robot> {
        val joined = MutableStateFlow<List<Robot>>(emptyList())
        try {
            return coroutineScope {
                devices.map { d -> async { connect(d).also { r -> joined.update { it + r } } } }.awaitAll()
            }
        } catch (e: Throwable) {
            joined.value.forEach { remove(it) }
            throw e
        }
    }

    /**
     * Discovers robots with [discoverer] and connects them all in parallel: with a [count], exactly that many (the
     * first found), failing with [RobotsNotFoundException] (which names those found) when fewer turn up within
     * [timeout]; without, all it finds within [timeout].
     */
    public suspend fun discoverAndConnect(discoverer: Discoverer, count: Int? = null, timeout: Duration = 10.seconds): List<Robot> {
        require(count == null || count >= 1) { "count must be at least 1, not $count" }
        val found = ArrayList<RobotDevice>()
        withTimeoutOrNull(timeout) {
            val flow = discoverer.discover()
            (if (count != null) flow.take(count) else flow).toList(found)
        }
        if (count != null && found.size < count) throw RobotsNotFoundException(count, found.toList(), timeout)
        return connectAll(found)
    }

    /**
     * Queues one movement on each robot so that they start at the same moment: each robot's command is prepared and
     * queued behind its earlier commands first, then all frames go out back to back. Suspends until every robot
     * acknowledged; returns the handles.
     */
    public suspend fun enqueueTogether(movements: Map<Robot, Movement>): Map<Robot, MovementHandle> = coroutineScope {
        val ready = movements.keys.associateWith { CompletableDeferred<Unit>() }
        val go = CompletableDeferred<Unit>()
        val launched = movements.map { (robot, movement) ->
            robot to async {
                try {
                    robot.locomotion.enqueue(movement) {
                        ready.getValue(robot).complete(Unit)
                        go.await()
                    }
                } finally {
                    ready.getValue(robot).complete(Unit) // a robot that fails early must not hold the others
                }
            }
        }
        launch {
            ready.values.awaitAll()
            go.complete(Unit)
        }
        launched.associate { (robot, d) -> robot to d.await() }
    }

    /**
     * Runs a movement program on each robot, all starting at the same moment: the first movements go out together
     * (as [enqueueTogether] sends them), the rest follow on each robot as its queue drains (see [Locomotion.runProgram]:
     * programs longer than [Locomotion.QUEUE_CAPACITY] are fed as the robot works through them). Suspends until
     * every program ended; returns how each movement ended, per robot, in program order. A robot whose movement does
     * not finish runs no more of its program; the others go on.
     *
     * ```
     * val square = List(4) { listOf(Movement.Straight(0.2, 0.1), Movement.Rotate(90.0, 0.1)) }.flatten()
     * fleet.runTogether(robots.associateWith { square })
     * fleet.awaitSettled()
     * ```
     */
    public suspend fun runTogether(programs: Map<Robot, List<Movement>>): Map<Robot, List<MovementResult>> {
        val first = enqueueTogether(programs.filterValues { it.isNotEmpty() }.mapValues { it.value.first() })
        return coroutineScope {
            programs.map { (robot, program) ->
                robot to async {
                    val queued = listOfNotNull(first[robot])
                    robot.locomotion.feed(queued, program.drop(queued.size).iterator())
                }
            }.associate { (robot, results) -> robot to results.await() }
        }
    }

    /** Suspends until every robot finished the movements this host queued. */
    public suspend fun awaitIdle() {
        coroutineScope { _robots.value.map { async { it.locomotion.awaitIdle() } }.awaitAll() }
    }

    /**
     * Suspends until every robot finished the movements this host queued and then reported a state at rest, so that
     * each one's odometry holds where it stopped (see [Locomotion.awaitSettled]).
     */
    public suspend fun awaitSettled() {
        coroutineScope { _robots.value.map { async { it.locomotion.awaitSettled() } }.awaitAll() }
    }

    /** Stops every robot (clears the queues). */
    public suspend fun stopAll(immediate: Boolean = false) {
        coroutineScope { _robots.value.map { async { it.locomotion.stop(immediate) } }.awaitAll() }
    }

    /** Closes [robot] and removes it from the fleet. */
    public fun remove(robot: Robot) {
        robot.close()
        _robots.update { it - robot }
    }

    /** Disconnects every robot (see [Robot.disconnect]) and suspends until all the fleet's coroutines ended; idempotent. */
    public suspend fun disconnect() {
        val all = _robots.value
        _robots.value = emptyList()
        for (r in all) r.disconnect()
        close()
        withContext(NonCancellable) { job.join() }
    }

    /**
     * Closes every robot without waiting for their coroutines (for `use {}`; see [Robot.close]); idempotent. The
     * scope that made the fleet completes once they ended.
     */
    override fun close() {
        _robots.value.forEach { it.close() }
        _robots.value = emptyList()
        job.complete()
    }
}

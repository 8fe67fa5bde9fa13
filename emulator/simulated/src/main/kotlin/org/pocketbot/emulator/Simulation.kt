package org.pocketbot.emulator

import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.ExperimentalCoroutinesApi
import kotlinx.coroutines.Job
import kotlinx.coroutines.async
import kotlinx.coroutines.test.StandardTestDispatcher
import kotlinx.coroutines.test.TestCoroutineScheduler
import org.pocketbot.sdk.RobotRuntime
import kotlin.random.Random
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * Runs [block] on the emulator's simulated clock and returns its result: a repeatable run, as fast as the CPU allows.
 *
 * [block], and the SDK's own work for every robot connected in its scope, run on this thread on virtual time that
 * advances in lockstep with the emulator, 1 ms at a time, whenever every coroutine waits: a `delay(2.seconds)` lasts
 * exactly 2000 emulator steps, a command timeout is measured in simulated time, and the same script with the same
 * world and seed gives the same [Emulator.stateHash] every time. The SDK's random choices come from [seed].
 *
 * Connect robots through [Emulator.discoverer] (in-process links); TCP endpoints run on wall-clock time and do not
 * belong in a simulated run. Code in [block] must not block its thread (`Thread.sleep`, `runBlocking`): nothing else
 * runs meanwhile, the simulation included. The emulator must not be running on its own thread ([Emulator.start]).
 *
 * ```
 * Emulator.local(robots = 1).use { emulator ->
 *     emulator.runSimulated {
 *         val robot = emulator.discoverer().discover().first().connect(this)
 *         robot.locomotion.enqueue(Movement.Straight(0.1, 0.2)).await()
 *         robot.close()
 *     }
 * }
 * ```
 *
 * Robots and fleets connected in the block's scope belong to it; those still open when [block] returns are closed
 * with the run.
 *
 * @param limit simulated time after which the run is abandoned with an [IllegalStateException] (a script that waits
 *   for something that never happens would otherwise simulate forever).
 */
@OptIn(ExperimentalCoroutinesApi::class)
public fun <T> Emulator.runSimulated(
    limit: Duration = Duration.INFINITE,
    seed: Long = config.seed,
    block: suspend CoroutineScope.() -> T,
): T {
    check(!isRunningOnItsOwn) { "the emulator runs on its own thread: stop() it before a simulated run" }
    val scheduler = TestCoroutineScheduler()
    val dispatcher = StandardTestDispatcher(scheduler, "simulation")
    val job = Job()
    val scope = CoroutineScope(dispatcher + job + RobotRuntime(dispatcher, Random(seed)))
    // The block's value, once it returned: robots and fleets it left open keep its coroutine from completing.
    val returned = CompletableDeferred<T>()
    val result = scope.async { block().also { returned.complete(it) } }
    val step = SimTime.toDuration(SimTime.STEP_TICKS)
    var simulated = Duration.ZERO
    try {
        while (true) {
            scheduler.runCurrent()
            if (returned.isCompleted || result.isCompleted) break
            check(simulated < limit) { "simulated run did not finish within $limit of simulated time" }
            step()
            scheduler.advanceTimeBy(step)
            simulated += step
        }
    } finally {
        // Everything the run left behind (robots not closed) ends with it.
        job.cancel()
        repeat(DRAIN_ROUNDS) {
            scheduler.advanceTimeBy(1.milliseconds)
            scheduler.runCurrent()
        }
    }
    return if (returned.isCompleted) returned.getCompleted() else result.getCompleted()
}

private const val DRAIN_ROUNDS = 10

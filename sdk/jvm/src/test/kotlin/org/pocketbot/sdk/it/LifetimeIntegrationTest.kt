package org.pocketbot.sdk.it

import kotlinx.coroutines.CoroutineName
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.Job
import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.debug.DebugProbes
import kotlinx.coroutines.delay
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.transport.TcpRobotDevice
import kotlin.test.assertEquals
import kotlin.test.assertIs
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * Robots and a fleet over real TCP links to the emulator, in real time, belong to the scope that made them: while they
 * are connected their coroutines are in that scope's job tree, the scope completes only once they are closed, and
 * after `close()`, after a cancelled scope and after a `coroutineScope { }` no coroutine of theirs and no thread they
 * started is left.
 */
class LifetimeIntegrationTest {
    @Test
    fun robotsAndAFleetOverTcpLeaveNoCoroutineAndNoThreadBehind() = withDebugProbes { Emulator.local(robots = 3, world = "open").use { emu ->
        val devices = emu.robots.map { TcpRobotDevice("127.0.0.1", it.startTcp(0)) }
        emu.start(Speed.Realtime(1.0))
        runBlocking(Dispatchers.Default) {
            // The process's socket loops and coroutine workers start with the first link and stay: not the robots'.
            coroutineScope { devices[0].connect(this, itOptions()).disconnect() }
            val threadsBefore = liveThreads()
            val coroutinesBefore = allCoroutines()

            // close(): the scope's job completes once everything the robot started ended (its goodbye included).
            val owner = Job()
            val robot = devices[0].connect(CoroutineScope(Dispatchers.Default + owner), itOptions())
            val working = coroutinesUnder(owner)
            assertTrue(working >= 4, "the robot's coroutines (reader, heartbeats, supervision, ...) run in the caller's scope: $working")
            robot.close()
            owner.complete()
            withTimeout(2.seconds) { owner.join() }
            assertEquals(0, coroutinesUnder(owner), "coroutines left after close()")
            assertIs<ConnectionState.Closed>(robot.connection.value)

            // A fleet whose scope is cancelled: every robot closes and nothing of them is left.
            val fleetOwner = Job()
            val fleet = Fleet(CoroutineScope(Dispatchers.Default + fleetOwner), itOptions())
            val robots = fleet.connectAll(devices)
            val fleetWorking = coroutinesUnder(fleetOwner)
            assertTrue(fleetWorking >= 3 * 4, "three robots' coroutines in the fleet's scope: $fleetWorking")
            fleetOwner.cancel()
            withTimeout(2.seconds) { fleetOwner.join() }
            assertEquals(0, coroutinesUnder(fleetOwner), "coroutines left after the fleet's scope was cancelled")
            robots.forEach { assertIs<ConnectionState.Closed>(it.connection.value) }

            // coroutineScope { } waits for the robot it connected: it returns after the close, not before.
            val started = System.nanoTime()
            coroutineScope {
                val r = devices[1].connect(this, itOptions())
                launch {
                    delay(300.milliseconds)
                    r.close()
                }
            }
            val waitedMs = (System.nanoTime() - started) / 1_000_000
            assertTrue(waitedMs >= 300, "coroutineScope returned after $waitedMs ms, before the robot closed at 300 ms")

            // The emulator's side of each link and the SDK's socket loops let go of the sockets: no thread left over.
            val deadline = System.nanoTime() + 2_000_000_000L
            var leftOver = liveThreads() - threadsBefore
            while (leftOver.isNotEmpty() && System.nanoTime() < deadline) {
                delay(50)
                leftOver = liveThreads() - threadsBefore
            }
            assertEquals(emptySet(), leftOver, "threads started by the robots and still alive")
            // Every coroutine of the process, also one a robot might have started outside its scope's tree.
            val coroutinesAfter = allCoroutines()
            println("lifetimes: one robot ran $working coroutines in its scope, three in a fleet $fleetWorking; left after: " +
                "${coroutinesAfter.size - coroutinesBefore.size} coroutines, ${leftOver.size} threads; coroutineScope waited $waitedMs ms")
            assertEquals(emptyList(), coroutinesAfter - coroutinesBefore, "coroutines of the robots still alive")
        }
    } }

    private fun <T> withDebugProbes(block: () -> T): T {
        DebugProbes.install()
        try {
            return block()
        } finally {
            DebugProbes.uninstall()
        }
    }

    /** Every coroutine alive in the process (DebugProbes), by its name and the identity of its job. */
    private fun allCoroutines(): List<String> =
        DebugProbes.dumpCoroutinesInfo().map { c ->
            "${c.context[CoroutineName]?.name ?: "coroutine"} ${c.job?.let { "${it::class.simpleName}@${System.identityHashCode(it)}" }}"
        }

    /** How many coroutines (jobs) are running in [job]'s tree, [job] itself not counted. */
    private fun coroutinesUnder(job: Job): Int = job.children.sumOf { 1 + coroutinesUnder(it) }

    /**
     * The live threads by name, but for kotlinx.coroutines' own pools (`Dispatchers.Default`'s workers, the executor
     * of delays), whose threads come and go with load and belong to the process, not to a robot, and the SDK's TCP
     * socket loops (`pocketbot-sockets-N`), shared by every TCP link of the process and started at the first one: which
     * test runs first decides whether they exist before this one counts.
     */
    private fun liveThreads(): Set<String> = Thread.getAllStackTraces().keys
        .filter { it.isAlive && !it.name.startsWith("DefaultDispatcher-worker") &&
            it.name != "kotlinx.coroutines.DefaultExecutor" && !it.name.startsWith("pocketbot-sockets-") }
        .map { "${it.name}#${it.id}" }
        .toSet()
}

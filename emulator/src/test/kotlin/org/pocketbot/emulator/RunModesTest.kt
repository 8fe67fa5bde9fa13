package org.pocketbot.emulator

import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import kotlin.test.Test
import org.pocketbot.emulator.world.Worlds
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.days
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.minutes
import kotlin.time.Duration.Companion.nanoseconds
import kotlin.time.Duration.Companion.seconds

/** Running on the emulator's own thread (speed, pause, single step) and finding robots in process. */
class RunModesTest {
    /** A wall clock the test moves by hand; the emulator's loop waits on it like on the real one. */
    private class HandClock : WallClock {
        @Volatile var nanos = 0L
        override fun nanoTime(): Long = nanos
        override fun sleep(millis: Long) = Thread.sleep(1) // give the test thread the lock; time moves only by hand
    }

    /** Waits (not measures) until [condition] holds: failing means the loop stopped, whatever the machine's load. */
    private fun eventually(what: String, condition: () -> Boolean) {
        val deadline = System.nanoTime() + 60_000_000_000L
        while (!condition()) {
            check(System.nanoTime() < deadline) { "never: $what" }
            Thread.sleep(1)
        }
    }

    @Test
    fun `an emulator stepped in blocks by runFor counts as running for a robot's connection`() {
        // Two robots far apart on the open floor: out of each other's reach, runFor steps them in blocks.
        Emulator.local(robots = 2, world = "open").use { emu ->
            val stepping = java.util.concurrent.atomic.AtomicBoolean(true)
            val stepper = Thread { while (stepping.get()) emu.runFor(100.milliseconds) }.apply { start() }
            try {
                assertTrue(runBlocking { emu.isStepped(2.seconds) }, "a connection would be told the emulator is not running")
            } finally {
                stepping.set(false)
                stepper.join()
            }
        }
    }

    @Test
    fun `runFor runs long spans exactly (ticks of a long span do not overflow)`() {
        assertEquals(400L * SimTime.TICKS_PER_SECOND, SimTime.fromDuration(400.seconds))
        assertEquals(1000L * 86_400 * SimTime.TICKS_PER_SECOND, SimTime.fromDuration(1000.days))
        assertEquals(31L, SimTime.fromDuration(999.nanoseconds), "rounded down: 999 ns is 31.97 ticks")
        Emulator(Worlds.load("straight"), EmulatorConfig(firmware = RealFirmware.image)).use { emu ->
            emu.runFor(10.minutes) // no robot: the steps are cheap, the arithmetic is what is tested
            assertEquals(SimTime.fromDuration(10.minutes), emu.timeTicks)
        }
    }

    @Test
    fun `real time follows the wall clock at its factor, pause stops time and single step advances 1 ms`() {
        val clock = HandClock()
        Emulator(Worlds.load("round"), EmulatorConfig(firmware = RealFirmware.image, wallClock = clock)).use { emu ->
            emu.addRobot()
            emu.start(Speed.Realtime(1.0))
            clock.nanos += 300_000_000 // 300 ms of wall time
            eventually("300 ms simulated") { emu.time.inWholeMilliseconds >= 300 }
            Thread.sleep(20)
            assertEquals(300, emu.time.inWholeMilliseconds, "real time does not run ahead of the wall clock")
            emu.stop()
            emu.start(Speed.Realtime(4.0)) // real time counts from the start
            clock.nanos += 100_000_000
            eventually("400 ms more at 4x") { emu.time.inWholeMilliseconds >= 700 }
            Thread.sleep(20)
            assertEquals(700, emu.time.inWholeMilliseconds, "4x the wall clock, no more")
            emu.pause()
            val t = emu.timeTicks
            clock.nanos += 1_000_000_000
            Thread.sleep(20)
            assertEquals(t, emu.timeTicks, "time moved while paused")
            emu.singleStep()
            assertEquals(t + SimTime.STEP_TICKS, emu.timeTicks)
            emu.speed = Speed.AsFastAsPossible
            emu.resume()
            eventually("as fast as possible runs without the wall clock") { emu.time.inWholeMilliseconds > 5_000 }
            emu.stop()
        }
    }

    @Test
    fun `in real time a fleet that one thread keeps up with is stepped on one thread, the other cores stay idle`() {
        val threads = java.lang.management.ManagementFactory.getThreadMXBean()
        fun workersCpuNs() = Thread.getAllStackTraces().keys.filter { it.name.startsWith("emulator-step-") }
            .sumOf { threads.getThreadCpuTime(it.id).coerceAtLeast(0) }
        RealFirmware.emulator("round").use { emu -> // the default config: as many stepping threads as cores
            repeat(8) { k -> // the panel's typical fleet, round the track
                val a = Math.toRadians(k * 45.0)
                emu.addRobot(pose = org.pocketbot.sdk.Pose.ofDegrees(0.4 + 0.3 * kotlin.math.cos(a), 0.4 + 0.3 * kotlin.math.sin(a), k * 45.0 + 90))
            }
            emu.runFor(3.seconds) // as fast as it goes: the JIT compiles the firmware, both modes are measured
            emu.start(Speed.Realtime(1.0))
            eventually("half a second in real time") { emu.time.inWholeMilliseconds >= 3500 }
            val cpu0 = workersCpuNs()
            val wall0 = System.nanoTime()
            eventually("1.5 s more") { emu.time.inWholeMilliseconds >= 5000 }
            emu.stop()
            val share = (workersCpuNs() - cpu0).toDouble() / (System.nanoTime() - wall0)
            // A worker that polls for work while there is none (every 50 us, as it once did) used 9 % here; one
            // stepping in parallel in real time spins after every 1 ms step for the next one, a third of a core.
            assertTrue(share < 0.05, "the other stepping threads used ${"%.0f".format(share * 100)} % of a core")
        }
    }

    @Test
    fun `the discoverer finds every robot and connects to it`() = RealFirmware.emulator("round").use { emu ->
        repeat(3) { emu.addRobot() }
        emu.start(Speed.Realtime(4.0))
        runBlocking {
            val devices = emu.discoverer().discover().toList()
            assertEquals(listOf("PocketBot-1", "PocketBot-2", "PocketBot-3"), devices.map { it.name })
            assertEquals("emulator:3", devices[2].address)
            val t = devices[2].open()
            t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 77L), 0))
            val hello = withTimeout(5000) {
                var h: Hello? = null
                while (h == null) {
                    val r = Frames.decode(t.incoming.receive())
                    if (r is FrameResult.Decoded && r.packet is Hello) h = r.packet as Hello
                }
                h
            }
            assertEquals(3, hello.robotId)
            t.close()
        }
        emu.stop()
    }
}

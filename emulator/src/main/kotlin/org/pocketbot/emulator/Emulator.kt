package org.pocketbot.emulator

import org.pocketbot.emulator.firmware.FirmwareEngine
import org.pocketbot.emulator.firmware.FirmwareImage
import org.pocketbot.emulator.internal.ParallelStepper
import org.pocketbot.emulator.physics.RobotParams
import org.pocketbot.emulator.transport.ControlPort
import org.pocketbot.emulator.transport.InProcessDiscoverer
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.emulator.transport.TcpEndpoint
import org.pocketbot.sdk.Pose
import org.pocketbot.emulator.world.World
import org.pocketbot.emulator.world.Worlds
import org.pocketbot.sdk.transport.Discoverer
import kotlinx.coroutines.CompletableDeferred
import kotlinx.coroutines.withTimeoutOrNull
import java.net.InetAddress
import java.security.MessageDigest
import java.nio.ByteBuffer
import kotlin.time.Duration

/** How fast simulated time runs when the emulator runs on its own thread. */
public sealed interface Speed {
    /** Simulated time runs at [factor] times the wall clock (1.0 = real time). */
    public class Realtime(public val factor: Double = 1.0) : Speed {
        init { require(factor > 0) { "factor must be positive" } }

        override fun equals(other: Any?): Boolean = other is Realtime && other.factor == factor
        override fun hashCode(): Int = factor.hashCode()
        override fun toString(): String = "Realtime(x$factor)"
    }

    /** As fast as the machine allows. */
    public data object AsFastAsPossible : Speed
}

/** Settings of an [Emulator]. */
public class EmulatorConfig(
    /** Seeds every random effect (sensor noise, encoder phases, link faults): same world + seed = same run. */
    public val seed: Long = 1,
    /** The firmware every robot runs; by default the build-time compiled firmware. */
    public val firmware: FirmwareImage? = null,
    public val robotParams: RobotParams = RobotParams(),
    public val noise: NoiseSettings = NoiseSettings(),
    /** Threads that step robots (the caller's included); results do not depend on it. */
    public val threads: Int = Runtime.getRuntime().availableProcessors().coerceIn(1, 8),
    /** Below this many robots one thread steps them all; from it on, the emulator measures serial and parallel stepping and uses the faster. */
    public val parallelFrom: Int = 4,
    /** The wall clock that paces [Speed.Realtime], in nanoseconds; tests put a clock of their own here. */
    public val wallClock: WallClock = WallClock.SYSTEM,
)

/** A wall clock for [Speed.Realtime] pacing: the time now, and a way to wait. */
public interface WallClock {
    public fun nanoTime(): Long
    public fun sleep(millis: Long)

    public companion object {
        /** The machine's monotonic clock. */
        public val SYSTEM: WallClock = object : WallClock {
            override fun nanoTime(): Long = System.nanoTime()
            override fun sleep(millis: Long) = Thread.sleep(millis)
        }
    }
}

/**
 * Runs simulated PocketBot2 robots, each with its own instance of the real firmware (WebAssembly under
 * Chicory), in lockstep 1 ms steps of simulated time: deterministic for a world and seed.
 *
 * Drive it either synchronously ([step], [runFor], [runUntil]; tests) or on its own thread ([start] with a
 * [Speed], [pause], [resume], [singleStep]; interactive use). All methods are safe to call from any thread.
 *
 * ```
 * Emulator(Worlds.load("round")).use { emu ->
 *     val robot = emu.addRobot()
 *     val transport = robot.openTransport()        // or emu.discoverer(), or robot.startTcp()
 *     emu.runFor(2.seconds)
 *     println(robot.truePose)
 * }
 * ```
 */
public class Emulator(world: World, public val config: EmulatorConfig = EmulatorConfig()) : AutoCloseable {
    private val lock = Any()
    internal val sim = SimWorld(world)
    private val image: FirmwareImage by lazy { config.firmware ?: FirmwareImage.compiled() }
    private val handles = ArrayList<RobotHandle>()
    private val stepper = ParallelStepper(config.threads)
    private val deferred = ArrayList<SimRobot>()
    /**
     * The longest block of steps a robot out of everyone's reach runs in a row (see [runLocked]); 1 turns blocks off.
     * `-Dpocketbot.emulator.blockMs=N` sets it, to measure what blocks buy: the results are the same.
     */
    private val blockMs = System.getProperty("pocketbot.emulator.blockMs")?.toIntOrNull()?.coerceIn(1, 50) ?: 8
    private val alone = ArrayList<SimRobot>()
    private val together = ArrayList<SimRobot>()
    private var serialNs = 0L
    private val modes = StepModeChooser(config.threads, config.parallelFrom) { (stepper.takeCounts() + " serial part ${serialNs / 1000} us").also { serialNs = 0 } }
    private var nowTicks = 0L
    private val stepWaiters = ArrayList<CompletableDeferred<Unit>>()

    @Volatile private var loop: Thread? = null
    @Volatile private var running = false
    @Volatile private var paused = false
    @Volatile public var speed: Speed = Speed.Realtime(1.0)
    @Volatile private var controlPort: ControlPort? = null
    private var closed = false // guarded by lock

    public val world: World get() = sim.spec

    /** What runs the robots' firmware (see [FirmwareImage.compiled]). */
    public val firmwareEngine: FirmwareEngine get() = image.engine

    /** Simulated time since the start, in 32 MHz ticks. */
    public val timeTicks: Long get() = synchronized(lock) { nowTicks }
    public val time: Duration get() = SimTime.toDuration(timeTicks)

    public val robots: List<RobotHandle> get() = synchronized(lock) { handles.toList() }

    public fun robot(id: Int): RobotHandle = robots.firstOrNull { it.id == id } ?: throw NoSuchElementException("no robot $id")

    /**
     * Adds a robot with [id] (default: next free, from 1) and boots its firmware at the current time.
     *
     * Without a [pose] the robot stands where no other robot or box is: at the first of the world's start poses
     * that is free, else on the first free spot of a grid over the floor, off the tape, facing +x (see
     * emulator/README.md, "Worlds"); an [IllegalStateException] says when the floor has no room left. A [pose] is
     * taken as given: a robot placed on another is pushed apart from it in the next step.
     */
    public fun addRobot(id: Int? = null, pose: Pose? = null): RobotHandle = synchronized(lock) {
        // Ids are bytes on the wire (1..254): a fleet larger than that reuses them, as real robots would have to.
        val rid = id ?: (handles.size % 254 + 1)
        require(rid in 1..254) { "robot id $rid out of 1..254" }
        require(id == null || handles.none { it.id == rid }) { "robot id $rid exists" }
        val start = pose ?: sim.freePlace(config.robotParams) ?: throw IllegalStateException(
            "no room for another robot in world ${world.name} (${world.widthM} x ${world.heightM} m, " +
                "${world.starts.size} start poses, ${handles.size} robots): give it a pose with addRobot(pose = ...)",
        )
        val r = SimRobot(rid, handles.size, config.robotParams, sim, image, start, config.seed, config.noise)
        r.bootAt(nowTicks)
        sim.robots += r
        RobotHandle(this, r, lock).also { handles += it }
    }

    /** Advances simulated time by [steps] milliseconds. */
    public fun step(steps: Int = 1) {
        repeat(steps) { synchronized(lock) { modes.pace = 0.0; stepLocked() } }
    }

    public fun runFor(duration: Duration) {
        val steps = SimTime.fromDuration(duration) / SimTime.STEP_TICKS
        var done = 0L
        while (done < steps) {
            val n = minOf(50L, steps - done).toInt()
            synchronized(lock) { modes.pace = 0.0; runLocked(n) }
            done += n
        }
    }

    /** Steps until [condition] holds (checked every step) or [timeout] of simulated time passed; true if it held. */
    public fun runUntil(timeout: Duration, condition: () -> Boolean): Boolean {
        val end = timeTicks + SimTime.fromDuration(timeout)
        while (timeTicks < end) {
            if (condition()) return true
            step()
        }
        return condition()
    }

    /**
     * Steps [steps] milliseconds, in blocks of up to [blockMs]: a robot that nothing can reach within a block (no
     * other robot or box within what IR, contact or a push could bridge in that time, whatever every robot does
     * meanwhile) runs the whole block in a row, exactly as it would in single steps, since nothing of the others
     * could reach it at a step's end. The rest are stepped a millisecond at a time, with IR and collisions in between.
     */
    private fun runLocked(steps: Int) {
        var left = steps
        while (left > 0) {
            val k = minOf(left, blockMs)
            if (k == 1 || sim.markAlone(k) == 0) repeat(k) { stepLocked() } else stepBlockLocked(k)
            left -= k
        }
    }

    private fun stepBlockLocked(ms: Int) {
        val t0 = nowTicks
        val rs = sim.robots
        val n = rs.size
        alone.clear(); together.clear()
        for (r in rs) if (r.alone) alone += r else together += r
        val parallel = modes.parallel(n)
        val start = System.nanoTime()
        if (parallel) stepper.run(alone.size) { i -> runAlone(alone[i], t0, ms) } else for (r in alone) runAlone(r, t0, ms)
        modes.record(parallel, System.nanoTime() - start, n, ms)
        // With everyone alone, what happens between robots at a step's end is nothing at all.
        if (together.isNotEmpty()) repeat(ms) { stepLocked(together) }
        advanceTo(t0 + ms * SimTime.STEP_TICKS)
    }

    /** [ms] steps of a robot that nothing reaches meanwhile: IR it sends is heard by no one, as at a step's end. */
    private fun runAlone(r: SimRobot, t0: Long, ms: Int) {
        r.deferred = false
        for (k in 0 until ms) {
            val t = t0 + k * SimTime.STEP_TICKS
            r.motorUpdate()
            r.moveAndRun(t, t + SimTime.STEP_TICKS)
            r.irOutCount = 0
        }
    }

    private fun stepLocked(rs: List<SimRobot> = sim.robots) {
        val t0 = nowTicks
        val t1 = t0 + SimTime.STEP_TICKS
        val n = rs.size
        val parallel = modes.parallel(sim.robots.size)
        val start = System.nanoTime()
        if (parallel) stepper.run(n) { i -> phaseA(rs[i], t0, t1) } else for (i in 0 until n) phaseA(rs[i], t0, t1)
        val phaseEnd = System.nanoTime()
        deferred.clear()
        for (i in 0 until n) if (rs[i].deferred) deferred += rs[i]
        if (deferred.isNotEmpty()) {
            sim.resolvePushes(deferred)
            for (r in deferred) r.moveAndRun(t0, t1)
        }
        sim.afterStep()
        val end = System.nanoTime()
        serialNs += end - phaseEnd
        if (rs === sim.robots) modes.record(parallel, end - start, n, 1)
        advanceTo(t1)
    }

    /** Simulated time moved on to [ticks], in a step or a block: whoever waits in [isStepped] learns it. */
    private fun advanceTo(ticks: Long) {
        nowTicks = ticks
        if (stepWaiters.isNotEmpty()) {
            stepWaiters.forEach { it.complete(Unit) }
            stepWaiters.clear()
        }
    }

    /**
     * Whether something steps this emulator: its own thread ([start]), or a step within [timeout] (a simulated run,
     * a test stepping it). A connection to a robot of an emulator that nothing steps would wait for answers that
     * never come: [org.pocketbot.emulator.transport.InProcessDevice] says so instead.
     */
    internal suspend fun isStepped(timeout: Duration): Boolean {
        if (loop != null) return true
        val next = CompletableDeferred<Unit>()
        synchronized(lock) { stepWaiters += next }
        val stepped = withTimeoutOrNull(timeout) { next.await() } != null
        if (!stepped) synchronized(lock) { stepWaiters -= next }
        return stepped || loop != null
    }

    private fun phaseA(r: SimRobot, t0: Long, t1: Long) {
        r.motorUpdate()
        r.deferred = r.contactBox >= 0
        if (!r.deferred) r.moveAndRun(t0, t1)
    }

    // ---- running on its own thread ------------------------------------------------------------------------------

    /** Runs on a background thread at [speed] until [stop] or [close]; real time counts from this call. */
    public fun start(speed: Speed = this.speed) {
        this.speed = speed
        if (loop != null) return
        running = true
        paused = false
        val wallStart = config.wallClock.nanoTime()
        val simStart = timeTicks
        loop = Thread({ runLoop(wallStart, simStart) }, "emulator-loop").apply { isDaemon = true; start() }
    }

    /** True while the emulator steps on its own thread ([start] until [stop]). */
    public val isRunningOnItsOwn: Boolean get() = loop != null

    public fun pause() { paused = true }
    public fun resume() { paused = false }
    public val isPaused: Boolean get() = paused

    /** While paused (or not started): advances exactly one 1 ms step. */
    public fun singleStep() { step(1) }

    public fun stop() {
        running = false
        loop?.let { if (it !== Thread.currentThread()) it.join(2000) }
        loop = null
    }

    private fun runLoop(wallStartNs: Long, simStartTicks: Long) {
        val clock = config.wallClock
        var wallStart = wallStartNs
        var simStart = simStartTicks
        var lastSpeed = speed
        var wasPaused = false
        while (running) {
            if (paused) { wasPaused = true; clock.sleep(5); continue }
            val sp = speed
            if (wasPaused || sp != lastSpeed) { wallStart = clock.nanoTime(); simStart = timeTicks; lastSpeed = sp; wasPaused = false }
            when (sp) {
                Speed.AsFastAsPossible -> synchronized(lock) { if (!closed) { modes.pace = 0.0; runLocked(20) } }
                is Speed.Realtime -> {
                    val elapsedNs = clock.nanoTime() - wallStart
                    val target = simStart + (elapsedNs * sp.factor * SimTime.TICKS_PER_SECOND / 1e9).toLong()
                    val behind = (target - timeTicks) / SimTime.STEP_TICKS
                    if (behind <= 0) clock.sleep(1)
                    else synchronized(lock) { if (!closed) { modes.pace = sp.factor; runLocked(minOf(behind, 200L).toInt()) } }
                }
            }
        }
    }

    // ---- connections ------------------------------------------------------------------------------------------

    /** Finds this emulator's robots, in process (each opens an [org.pocketbot.emulator.transport.InProcessTransport]). */
    public fun discoverer(): Discoverer = InProcessDiscoverer { robots.map { it.device() } }

    /**
     * Opens a TCP endpoint (SLIP frames, like a Bluetooth serial link) for every robot on [listen], robot i at
     * [basePort] + i (0: any free port), and the control port (see emulator/README.md) at [controlPort]
     * (0: any free port, -1: none). Returns the control port's number, or -1.
     *
     * [listen] is the loopback address unless told otherwise: only programs on this machine reach the robots.
     * [ListenAddress.ANY] puts them on the network (a phone on the same Wi-Fi), [ListenAddress.reachable] says at
     * which addresses. Endpoints opened before are closed first. Throws [java.net.BindException] when a port is
     * taken or [listen] is no address of this machine; then nothing is left open.
     */
    public fun startTcp(basePort: Int = 0, controlPort: Int = -1, listen: InetAddress = ListenAddress.LOOPBACK): Int {
        stopTcp()
        try {
            for ((i, h) in robots.withIndex()) h.startTcp(if (basePort == 0) 0 else basePort + i, listen)
            return startControlPort(controlPort, listen) { it.tcpPort }
        } catch (e: java.io.IOException) {
            stopTcp()
            throw e
        }
    }

    /**
     * Opens only the control port (see emulator/README.md) on [listen]:[controlPort] (0: any free port, -1: none),
     * listing for each robot the TCP port [portOf] names: for robots reached some other way than [startTcp], such as
     * the Bluetooth gateway's RFCOMM endpoints. Returns the port's number, or -1. [stopTcp] closes it.
     */
    public fun startControlPort(controlPort: Int, listen: InetAddress, portOf: (RobotHandle) -> Int): Int {
        if (controlPort < 0) return -1
        this.controlPort?.close()
        val cp = ControlPort(listen, controlPort, { robots }, portOf)
        this.controlPort = cp
        return cp.port
    }

    /** Closes every TCP endpoint and the control port; hosts connected over TCP lose the link. */
    public fun stopTcp() {
        controlPort?.close()
        controlPort = null
        for (h in robots) h.closeTcp()
    }

    // ---- ground truth -----------------------------------------------------------------------------------------

    /**
     * How many times two robot bodies were found overlapping at the end of a step (and pushed apart) since the
     * start: 0 means no robot ever touched another. Ground truth for tests of multi-robot behaviour.
     */
    public val robotContacts: Long get() = synchronized(lock) { sim.robotContacts }

    /** Positions of the world's boxes now (same order as [World.boxes]). */
    public fun boxes(): List<Pose> = synchronized(lock) { sim.boxes.map { Pose.ofDegrees(it.x, it.y, it.spec.angleDeg) } }

    /**
     * How far box [index] is from the tape now (ground truth): the shortest distance from its outline to the edge of
     * any tape, in metres (outline sampled every millimetre), 0 when its outline touches tape.
     */
    public fun boxClearanceM(index: Int = 0): Double = synchronized(lock) {
        val b = sim.boxes[index]
        val hw = b.spec.widthM / 2; val hh = b.spec.heightM / 2
        val c = kotlin.math.cos(b.angle); val s = kotlin.math.sin(b.angle)
        var best = Double.POSITIVE_INFINITY
        fun edge(x0: Double, y0: Double, x1: Double, y1: Double) {
            val n = maxOf(1, (kotlin.math.hypot(x1 - x0, y1 - y0) * 1000).toInt())
            for (k in 0..n) {
                val lx = x0 + (x1 - x0) * k / n; val ly = y0 + (y1 - y0) * k / n
                best = minOf(best, sim.surface.distanceToTapeEdge(b.x + lx * c - ly * s, b.y + lx * s + ly * c))
            }
        }
        edge(-hw, -hh, hw, -hh); edge(hw, -hh, hw, hh); edge(hw, hh, -hw, hh); edge(-hw, hh, -hw, -hh)
        best.coerceAtLeast(0.0)
    }

    /**
     * A hash of everything simulated: time, every robot's true pose, wheel travel and whole firmware memory,
     * the bytes each of its links delivered to a host (count and CRC-32), and the boxes. Two runs of the same world, seed and host traffic give the same hash.
     */
    public fun stateHash(): String = synchronized(lock) {
        val md = MessageDigest.getInstance("SHA-256")
        val buf = ByteBuffer.allocate(8 * 8)
        fun put(vararg v: Double) { buf.clear(); for (d in v) buf.putDouble(d); md.update(buf.array(), 0, buf.position()) }
        buf.clear(); buf.putLong(nowTicks); md.update(buf.array(), 0, 8)
        for (r in sim.robots) {
            put(r.x, r.y, r.theta, r.distL, r.distR, r.vl, r.vr)
            val mem = r.firmware.memory
            md.update(mem.readBytes(0, mem.size))
            for (l in r.links.all) { buf.clear(); buf.putLong(l.bytesToHost); buf.putLong(l.bytesToHostCrc); md.update(buf.array(), 0, 16) }
        }
        for (b in sim.boxes) put(b.x, b.y)
        md.digest().joinToString("") { "%02x".format(it) }
    }

    override fun close() {
        stop()
        stopTcp()
        for (h in robots) { h.detachH4(); h.sim.links.dropConnections("emulator closed") }
        // Under the lock: a loop thread that outlived stop()'s wait is between steps when the firmware goes.
        synchronized(lock) {
            closed = true
            for (r in sim.robots) r.firmware.close()
        }
        stepper.close()
    }

    public companion object {
        /** An emulator of [world] (a name from emulator/worlds) with [robots] robots at the world's start poses. */
        public fun local(robots: Int = 1, world: String = "straight", config: EmulatorConfig = EmulatorConfig()): Emulator =
            Emulator(Worlds.load(world), config).also { emu -> repeat(robots) { emu.addRobot() } }
    }
}

/**
 * Picks serial or parallel stepping by measuring both: handing a step to other threads pays off only when the
 * step is long enough and the other cores are free, which depends on the fleet and on the machine's load at
 * the time. Either mode gives exactly the same results.
 *
 * Kept to a clock ([pace]), the emulator steps serially whenever one thread keeps up with half a core or less:
 * there a second thread would not make it any faster, only cost CPU (the hand-over and the waiting for the next
 * step), which is what a user running a few robots in real time next to the panel would pay for nothing.
 */
private class StepModeChooser(private val threads: Int, private val parallelFrom: Int, private val counts: () -> String) {
    private var robots = -1
    private var current = false
    private var steps = 0
    private var epochNs = 0L
    private var epochs = 0
    private val avgNs = doubleArrayOf(Double.NaN, Double.NaN) // serial, parallel

    /** Simulated ms to step per wall-clock ms while kept to a clock ([Speed.Realtime]), 0 while as fast as possible. */
    var pace = 0.0

    fun parallel(n: Int): Boolean {
        if (threads <= 1 || n < parallelFrom) return false
        if (n != robots) { robots = n; avgNs.fill(Double.NaN); current = pace == 0.0; steps = 0; epochNs = 0; epochs = 0 }
        return current
    }

    /** [ns] spent stepping [n] robots [ms] milliseconds. */
    fun record(parallel: Boolean, ns: Long, n: Int, ms: Int) {
        if (threads <= 1 || n < parallelFrom || n != robots || parallel != current) return
        epochNs += ns
        steps += ms
        if (steps < EPOCH) return
        val k = if (current) 1 else 0
        val perStep = epochNs.toDouble() / steps
        avgNs[k] = if (avgNs[k].isNaN()) perStep else avgNs[k] * 0.5 + perStep * 0.5
        steps = 0; epochNs = 0; epochs++
        if (DEBUG) System.err.println("step modes: robots=$robots epoch=$epochs ${if (k == 1) "parallel" else "serial"} ${"%.1f".format(perStep / 1000)} us/step; avg serial=${"%.1f".format(avgNs[0] / 1000)} parallel=${"%.1f".format(avgNs[1] / 1000)} tasks by thread ${counts()}")
        val other = 1 - k
        current = when {
            serialKeepsPace() -> false
            avgNs[other].isNaN() -> other == 1
            epochs % PROBE_EVERY == 0 -> other == 1 // look at the other mode again now and then
            else -> avgNs[1] < avgNs[0]
        }
    }

    private fun serialKeepsPace() = pace > 0 && !avgNs[0].isNaN() && avgNs[0] * pace <= PACED_SERIAL_NS_PER_MS

    private companion object {
        val DEBUG = System.getProperty("pocketbot.emulator.debugModes") == "true"
        /** Serial stepping that needs at most this much of each wall-clock millisecond (half a core) keeps pace. */
        const val PACED_SERIAL_NS_PER_MS = 500_000.0
        const val EPOCH = 250
        const val PROBE_EVERY = 8
    }
}

package org.pocketbot.emulator.bench

import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.EmulatorConfig
import org.pocketbot.emulator.firmware.FirmwareEngine
import org.pocketbot.emulator.firmware.FirmwareImage
import org.pocketbot.sdk.Pose
import org.pocketbot.emulator.world.Point
import org.pocketbot.emulator.world.Tape
import org.pocketbot.emulator.world.World
import org.pocketbot.emulator.world.Worlds
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.HostRole
import org.pocketbot.protocol.LineFollow
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.SetRole
import org.pocketbot.protocol.Slip
import kotlin.math.abs
import kotlin.math.ceil
import kotlin.math.hypot
import kotlin.math.sqrt
import kotlin.system.exitProcess
import kotlin.time.Duration.Companion.seconds

/**
 * `make bench-emulator`: how fast the emulator runs fleets of line-following robots on the round track.
 * Prints per fleet size and firmware engine `emulator robots=<N> realtime_factor=<X> native_ratio=<Y> engine=<E>`,
 * `emulator robots=<N> cpu_us_per_robot_ms=<X> engine=<E>` (CPU of the whole process per robot and simulated
 * millisecond: the cost curve over N) and `emulator robots=<N> heap_bytes_per_robot=<X> engine=<E>` (live heap after a
 * GC, less the empty emulator's) on stdout, and `native robots=<N> cpu_us_per_robot_ms=<X>` for the native fleet.
 * On stderr per fleet: the realtime factor of each simulated second (lowest, median, highest: how much the machine
 * varied during the run), and two hashes of the end state: `state_hash` of everything simulated, firmware memory
 * included, and `pose_hash` of the robots' true poses alone, which stays the same for a firmware build that differs
 * only in its code or memory layout (another compiler flag) and behaves the same. Both engines give the same hashes:
 * the bench says so and exits with status 1 when they do not.
 * The fleet shares a floor of round tracks (thesis A.3) laid side by side, three robots per track.
 * Args: fleet sizes (default 1 3 10 30 100 300 1000). `-Dpocketbot.bench.engines=native,chicory` picks the engines
 * (default: both when the native one runs here), which run in turn for each fleet, between the native fleet's runs.
 *
 * Internal: a program of this repository (`make bench-emulator`), not part of the library's API.
 */
internal fun main(args: Array<String>) {
    val sizes = args.mapNotNull { it.toIntOrNull() }.ifEmpty { listOf(1, 3, 10, 30, 100, 300, 1000) }
    val images = engines().map { FirmwareImage.compiled(it) }
    // Warm-up: let the JIT compile the firmware (under Chicory) and the emulator before anything is measured.
    for (image in images) {
        run(image, 10, measureS = 40, warmS = 1)
        run(image, 100, measureS = 2, warmS = 1)
    }
    val native = System.getProperty("pocketbot.bench.native")?.let { NativeFleet(java.io.File(it)) }
    var disagreements = 0
    for (n in sizes) {
        // The native fleet runs just before and just after the emulator, so the machine's drift falls on both sides.
        val nativeBefore = native?.run(n)
        val results = images.map { it.engine to run(it, n) }
        val nativeUs = nativeBefore?.let { (it + native.run(n)) / 2 }
        for ((engine, result) in results) {
            val e = " engine=${engine.name.lowercase()}"
            val ratio = nativeUs?.let { " native_ratio=${"%.2f".format(result.cpuUsPerRobotMs / it)}" } ?: ""
            println("emulator robots=$n realtime_factor=${"%.2f".format(result.factor)}$ratio$e")
            println("emulator robots=$n cpu_us_per_robot_ms=${"%.2f".format(result.cpuUsPerRobotMs)}$e")
            println("emulator robots=$n heap_bytes_per_robot=${result.heapBytesPerRobot}$e")
        }
        if (nativeUs != null) println("native robots=$n cpu_us_per_robot_ms=${"%.2f".format(nativeUs)}")
        System.out.flush()
        for ((engine, result) in results) {
            val perSecond = result.secondFactors.sorted()
            System.err.println(
                "  robots=$n engine=${engine.name.lowercase()} simulated=${result.simulatedS}s wall=${"%.2f".format(result.wallS)}s " +
                    "on_line=${result.onLine}/$n threads=${result.threads} " +
                    "cpu_us_per_robot_ms=${"%.2f".format(result.cpuUsPerRobotMs)} loadavg=${loadAverage()}\n" +
                    "    realtime_factor per simulated second: lowest ${"%.2f".format(perSecond.first())} " +
                    "median ${"%.2f".format(perSecond[perSecond.size / 2])} highest ${"%.2f".format(perSecond.last())}; " +
                    "state_hash=${result.stateHash} pose_hash=${result.poseHash}",
            )
        }
        // The engines must agree bit for bit (DeterminismAndFaultsTest holds them to it too): a benchmark whose
        // engines diverge measures two different simulations.
        if (results.map { (_, r) -> r.stateHash to r.poseHash }.distinct().size > 1) {
            System.err.println("emulator robots=$n: the engines' state hashes differ")
            disagreements++
        }
    }
    if (disagreements > 0) exitProcess(1)
}

/** The engines to compare: `-Dpocketbot.bench.engines`, or both when the native one can run. */
private fun engines(): List<FirmwareEngine> =
    System.getProperty("pocketbot.bench.engines")?.split(',')?.map { FirmwareEngine.valueOf(it.trim().uppercase()) }
        ?: listOfNotNull(FirmwareImage.compiled().engine.takeIf { it == FirmwareEngine.NATIVE }, FirmwareEngine.CHICORY)

/**
 * The same fleet natively (firmware/native/fleet.c, built by `make -C firmware native-fleet`): the firmware's wasm
 * compiled to machine code, one instance per robot, driven as the emulator drives it, on one thread. Its CPU time
 * per robot and simulated millisecond is what the emulator's is compared with (`native_ratio`).
 */
private class NativeFleet(private val binary: java.io.File) {
    private val round = Worlds.load("round")
    private val track = round.tapes.single() as Tape.Arc

    /** CPU microseconds per robot and simulated millisecond for [n] robots. */
    fun run(n: Int): Double {
        val starts = round.starts.take(3).flatMap { listOf(it.xM, it.yM, it.headingDeg) }
        val frame = Slip.encode(Frames.encode(LineFollow(1, 0, 0f), 1)).joinToString("") { "%02x".format(it) }
        val args = listOf(binary.path, "$n", "${warmSeconds(n)}", "${measureSeconds(n)}", "${round.widthM}", "${track.center.x}",
            "${track.center.y}", "${track.radiusM}", "${track.widthM}", "${round.ambientAdc}") + starts.map { "$it" } + frame
        val process = ProcessBuilder(args).redirectError(ProcessBuilder.Redirect.INHERIT).start()
        val out = process.inputStream.bufferedReader().readText()
        check(process.waitFor() == 0) { "${binary.path} failed: $out" }
        System.err.print("  " + out)
        return Regex("cpu_us_per_robot_ms=([0-9.]+)").find(out)?.groupValues?.get(1)?.toDouble() ?: error("no result from ${binary.path}: $out")
    }
}

private fun warmSeconds(n: Int) = if (n >= 1000) 1 else 2

private fun measureSeconds(n: Int) =
    System.getProperty("pocketbot.bench.seconds")?.toIntOrNull() ?: when { n <= 1 -> 30; n <= 10 -> 20; n <= 100 -> 5; else -> 3 }

private fun loadAverage(): String =
    runCatching { java.io.File("/proc/loadavg").readText().split(' ').take(3).joinToString(",") }.getOrDefault("?")

private class Result(
    val factor: Double, val simulatedS: Int, val wallS: Double, val onLine: Int, val threads: Int,
    val cpuUsPerRobotMs: Double, val heapBytesPerRobot: Long, val secondFactors: List<Double>, val stateHash: String,
    val poseHash: String,
)

/** Live heap after a full collection, in bytes. */
private fun liveHeap(): Long {
    val rt = Runtime.getRuntime()
    repeat(3) { System.gc() }
    return rt.totalMemory() - rt.freeMemory()
}

private fun run(image: FirmwareImage, n: Int, measureS: Int? = null, warmS: Int? = null): Result {
    val round = Worlds.load("round")
    val track = round.tapes.single() as Tape.Arc
    val tracks = ceil(n / 3.0).toInt()
    val cols = ceil(sqrt(tracks.toDouble())).toInt()
    val rows = ceil(tracks.toDouble() / cols).toInt()
    val tile = round.widthM
    val world = World(
        name = "round-x$tracks", widthM = tile * cols, heightM = tile * rows, ambientAdc = round.ambientAdc,
        tapes = List(tracks) { k ->
            val center = Point(track.center.x + tile * (k % cols), track.center.y + tile * (k / cols))
            Tape.Arc(center, track.radiusM, track.startDeg, track.sweepDeg, track.widthM, track.colour)
        },
    )
    val config = System.getProperty("pocketbot.bench.threads")?.toIntOrNull()
        ?.let { EmulatorConfig(seed = 42, firmware = image, threads = it) } ?: EmulatorConfig(seed = 42, firmware = image)
    Emulator(world, config).use { emu ->
        val emptyHeap = liveHeap()
        // A host that drives each robot (hello_request, set_role) and starts its line following; acknowledged commands
        // carry non-zero sequence numbers.
        val frame = Slip.encode(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 0xBE4C), 1)) +
            Slip.encode(Frames.encode(SetRole(HostRole.DRIVE.code, "bench"), 2)) +
            Slip.encode(Frames.encode(LineFollow(1, 0, 0f), 3))
        for (i in 0 until n) {
            val k = i / 3
            val s = round.starts[i % 3]
            val pose = Pose.ofDegrees(s.xM + tile * (k % cols), s.yM + tile * (k / cols), s.headingDeg)
            val r = emu.addRobot(pose = pose)
            r.hostSendRaw(frame)
        }
        val warm = warmS ?: warmSeconds(n)
        emu.runFor(warm.seconds)
        val heapPerRobot = (liveHeap() - emptyHeap) / n
        val simS = measureS ?: measureSeconds(n)
        val os = java.lang.management.ManagementFactory.getOperatingSystemMXBean() as com.sun.management.OperatingSystemMXBean
        val cpu0 = os.processCpuTime
        val t0 = System.nanoTime()
        val secondFactors = List(simS) {
            val start = System.nanoTime()
            emu.runFor(1.seconds)
            1e9 / (System.nanoTime() - start)
        }
        val wall = (System.nanoTime() - t0) / 1e9
        val cpuUs = (os.processCpuTime - cpu0) / 1e3
        var onLine = 0
        for ((i, r) in emu.robots.withIndex()) {
            val k = i / 3
            val cx = track.center.x + tile * (k % cols); val cy = track.center.y + tile * (k / cols)
            val p = r.truePose
            if (abs(hypot(p.xM - cx, p.yM - cy) - track.radiusM) < 0.01 && r.trueWheelDistances.leftM > 0.2) onLine++
        }
        val poseHash = java.security.MessageDigest.getInstance("SHA-256").run {
            val pose = java.nio.ByteBuffer.allocate(24)
            for (r in emu.robots) r.truePose.let { update(pose.clear().putDouble(it.xM).putDouble(it.yM).putDouble(it.headingRad).array()) }
            digest().joinToString("") { "%02x".format(it) }
        }
        return Result(
            simS / wall, simS, wall, onLine, config.threads, cpuUs / (n * simS * 1000.0), heapPerRobot, secondFactors,
            emu.stateHash().take(16), poseHash.take(16),
        )
    }
}

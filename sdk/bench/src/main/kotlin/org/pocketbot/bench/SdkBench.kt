package org.pocketbot.bench

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import org.openjdk.jmh.profile.GCProfiler
import org.openjdk.jmh.runner.Runner
import org.openjdk.jmh.runner.options.OptionsBuilder
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.emulator.link.LinkSettings
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.StateReduced
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.StateUpdate
import org.pocketbot.sdk.SyncMode
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.TcpRobotDevice
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * `make bench-sdk`: every result is one line `sdk <metric>=<value>`; ratios are taken within this one run.
 *
 *   java -cp sdk/bench/target/classes:$(cat sdk/bench/target/classpath.txt) org.pocketbot.bench.SdkBenchKt [codec] [realtime] [connect] [fleet] [ack] [broker-fleet]
 */
fun main(args: Array<String>) {
    val which = args.toSet().ifEmpty { setOf("codec", "realtime", "connect", "fleet", "ack", "broker-fleet") }
    if ("codec" in which) codec()
    if ("ack" in which) ack()
    if ("broker-fleet" in which) brokerFleet()
    if ("connect" in which) connect()
    if ("realtime" in which) realtime()
    if ("fleet" in which) fleet()
    // One fleet run, for profiling (under JFR): fleet-tcp-<n>, fleet-tcp-ktor-<n> or fleet-in-process-<n>.
    which.firstOrNull { it.startsWith("fleet-") }?.let { arg ->
        val label = arg.removePrefix("fleet-").substringBeforeLast('-')
        val link = FleetBench.Link.entries.first { it.label == label }
        val r = FleetBench.run(arg.substringAfterLast('-').toInt(), link, seconds = 10)
        report(r)
    }
}

/**
 * Fleet scale (FleetBench): [FLEET] robots at 100 Hz full state each over TCP on the SDK's socket loop, over TCP on
 * ktor-network's sockets, and in process, interleaved in [FLEET_ROUNDS] rounds so that the three meet the same load
 * (the machine is shared: compare within a round). Robots per core: how many robots at 100 full states a second one
 * core carries at the CPU each update cost the SDK (the process's CPU without the stand-in robots' threads, over the
 * updates delivered); the goal is >= 1000 with p99 latency <= 5 ms, printed beside it (a loaded machine, with
 * another program's threads ahead of the SDK's, shows in p99 first). Each metric is the median of the rounds and
 * their range, beside the load average before and after.
 */
private fun fleet() {
    line("fleet_load_average_before", loadAverage())
    val links = FleetBench.Link.entries.filter { !it.broker }
    val rounds = List(FLEET_ROUNDS) { links.associateWith { FleetBench.run(FLEET, it, seconds = 5).also(::report) } }
    line("fleet_load_average_after", loadAverage())
    for (link in links) {
        val suffix = when (link) {
            FleetBench.Link.TCP -> ""
            FleetBench.Link.TCP_KTOR -> "_ktor"
            else -> "_in_process"
        }
        val rs = rounds.map { it.getValue(link) }
        line("fleet_robots_per_core$suffix", spread(rs.map { 1e6 / (it.usPerUpdate * UPDATES_PER_ROBOT_SECOND) }, "%.0f"))
        line("fleet_us_per_update$suffix", spread(rs.map { it.usPerUpdate }, "%.2f"))
        line("fleet_p99_ms$suffix", spread(rs.map { it.p99Ms }, "%.2f"))
        line("fleet_timed_share$suffix", spread(rs.map { 100.0 * it.timed / it.updates.coerceAtLeast(1) }, "%.1f%%"))
    }
    // What ktor's sockets cost per update against the SDK's loop, round by round.
    line("fleet_ktor_cost_ratio", spread(rounds.map { it.getValue(FleetBench.Link.TCP_KTOR).usPerUpdate / it.getValue(FleetBench.Link.TCP).usPerUpdate }, "%.2f"))
}

/**
 * Command to acknowledgement (AckBench) of one emulated robot in real time, directly over TCP, through one broker and
 * through a bridged pair (gateway on the room broker, client on the central one), in [ACK_ROUNDS] rounds that take
 * the three paths in turn (the machine is shared: compare within the run); each metric is the median of the rounds
 * and their range, beside the load average. The robot's own link is made as fast as the emulator allows (10 Mbaud,
 * no latency: what is left is the firmware's 1 ms step), so the figures are the host's path; `tcp_uart_ack_*` is
 * the direct path over the emulator's default link, a 115200-baud UART with 2 ms latency that also carries the
 * robot's 100 Hz state, as a real robot's serial or Bluetooth link does.
 */
private fun ack() {
    line("ack_load_average_before", loadAverage())
    val rounds = List(ACK_ROUNDS) {
        Emulator.local(robots = 1).use { emu ->
            val sim = emu.robots.single()
            sim.link = LinkSettings(baud = 10_000_000, latency = Duration.ZERO)
            emu.start(Speed.Realtime(1.0))
            val port = sim.startTcp(0)
            val tcp = ackOver { TcpRobotDevice("127.0.0.1", port) }
            val broker = runBlocking { BrokerPath.start(listOf(sim.device())) }.use { path -> ackOver { path.devices.single() } }
            val bridged = runBlocking { BrokerPath.start(listOf(sim.device()), bridged = true) }.use { path -> ackOver { path.devices.single() } }
            emu.stop()
            mapOf("tcp" to tcp, "broker" to broker, "bridged" to bridged)
        }
    }
    val uart = Emulator.local(robots = 1).use { emu ->
        emu.start(Speed.Realtime(1.0))
        val port = emu.robots.single().startTcp(0)
        ackOver { TcpRobotDevice("127.0.0.1", port) }.also { emu.stop() }
    }
    line("ack_load_average_after", loadAverage())
    for (path in listOf("tcp", "broker", "bridged")) {
        line("${path}_ack_p50_ms", spread(rounds.map { it.getValue(path).p50Ms }, "%.3f"))
        line("${path}_ack_p99_ms", spread(rounds.map { it.getValue(path).p99Ms }, "%.3f"))
    }
    line("broker_ack_p50_vs_tcp", spread(rounds.map { it.getValue("broker").p50Ms / it.getValue("tcp").p50Ms }, "%.2fx"))
    line("bridged_ack_p50_vs_tcp", spread(rounds.map { it.getValue("bridged").p50Ms / it.getValue("tcp").p50Ms }, "%.2fx"))
    line("tcp_uart_ack_p50_ms", "%.3f".format(uart.p50Ms))
    line("tcp_uart_ack_p99_ms", "%.3f".format(uart.p99Ms))
}

/** AckBench over the device [device] makes, in a scope of its own. */
private fun ackOver(device: suspend () -> RobotDevice): AckBench.Result = runBlocking {
    val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
    try {
        AckBench.run(scope, device())
    } finally {
        scope.cancel()
    }
}

private const val ACK_ROUNDS = 3

/**
 * State through one broker (FleetBench over [FleetBench.Link.BROKER] and [FleetBench.Link.BROKER_UNBATCHED]): a
 * gateway serves [BROKER_FLEET_SIZES] stand-in robots at 100 full states a second each, a fleet client in the same
 * process receives them through Mosquitto; batched (the default 10 ms window) and unbatched in turn,
 * [BROKER_FLEET_ROUNDS] rounds. At each size: the share of the offered states that arrived and their p99 latency
 * from the stand-in to the client's collector. At the largest: state frames and up messages a second the broker
 * carried, the broker's CPU (in cores), and from it the robots at 100 Hz one broker core carries (the goal is >= 500
 * batched).
 */
private fun brokerFleet() {
    line("broker_fleet_load_average_before", loadAverage())
    val modes = listOf(FleetBench.Link.BROKER, FleetBench.Link.BROKER_UNBATCHED)
    fun suffix(mode: FleetBench.Link) = if (mode == FleetBench.Link.BROKER) "batched" else "unbatched"
    val rounds = List(BROKER_FLEET_ROUNDS) {
        BROKER_FLEET_SIZES.associateWith { n -> modes.associateWith { FleetBench.run(n, it, BROKER_FLEET_SECONDS).also(::report) } }
    }
    line("broker_fleet_load_average_after", loadAverage())
    // How many robots one gateway (with the client in the same process) keeps up with: the share of the offered
    // states that arrived, and their p99 latency, at each size.
    for (n in BROKER_FLEET_SIZES) for (mode in modes) {
        val rs = rounds.map { it.getValue(n).getValue(mode) }
        line("gateway_delivered_share_${suffix(mode)}_$n", spread(rs.map { 100.0 * it.updates / (n * UPDATES_PER_ROBOT_SECOND * BROKER_FLEET_SECONDS.toDouble()) }, "%.1f%%"))
        line("gateway_state_p99_ms_${suffix(mode)}_$n", spread(rs.map { it.p99Ms }, "%.2f"))
    }
    val n = BROKER_FLEET_SIZES.last()
    line("broker_fleet_robots", n.toString())
    for (mode in modes) {
        val rs = rounds.map { it.getValue(n).getValue(mode) }
        val loads = rs.map { checkNotNull(it.broker) }
        val s = suffix(mode)
        line("broker_states_per_s_$s", spread(loads.map { it.framesPerS }, "%.0f"))
        line("broker_messages_per_s_$s", spread(loads.map { it.messagesPerS }, "%.0f"))
        line("broker_cpu_cores_$s", spread(loads.map { it.brokerCores }, "%.2f"))
        line("broker_robots_per_core_$s", spread(loads.map { it.framesPerS / UPDATES_PER_ROBOT_SECOND / it.brokerCores.coerceAtLeast(1e-3) }, "%.0f"))
        line("gateway_client_us_per_update_$s", spread(rs.map { it.usPerUpdate }, "%.2f"))
    }
}

private val BROKER_FLEET_SIZES = listOf(250, 500)
private const val BROKER_FLEET_ROUNDS = 2
private const val BROKER_FLEET_SECONDS = 5

private const val FLEET = 1000
private const val FLEET_ROUNDS = 3
private const val UPDATES_PER_ROBOT_SECOND = 100

/** The median of [values] and their range: `1520 (1480-1570)`. */
private fun spread(values: List<Double>, format: String): String {
    val sorted = values.sorted()
    return "${format.format(sorted[sorted.size / 2])} (${format.format(sorted.first())}-${format.format(sorted.last())})"
}

/** The 1, 5 and 15 minute load averages (other programs' load on this machine). */
private fun loadAverage(): String =
    runCatching { java.io.File("/proc/loadavg").readText().split(' ').take(3).joinToString(" ") }
        .getOrElse { "%.2f".format(java.lang.management.ManagementFactory.getOperatingSystemMXBean().systemLoadAverage) }

private fun report(r: FleetBench.Result) = System.err.println(
    "  fleet ${r.transport.label} robots=${r.n} cores=${"%.2f".format(r.cores)} us_per_update=${"%.2f".format(r.usPerUpdate)} " +
        "p99_ms=${"%.2f".format(r.p99Ms)} updates=${r.updates} timed=${r.timed} late=${r.late}",
)

private fun line(metric: String, value: String) = println("sdk $metric=$value")

/**
 * The state codec (JMH, [StateCodecBench]) at two levels. Payload: SDK decode of the 88 payload bytes + encode to
 * a new payload, against Javolution reading the same 88 bytes (new Struct per packet as the thesis did, and one
 * reused Struct), and against Javolution reading and writing them (the same work as the SDK). Frame: SDK CRC
 * check + decode of the 93-byte frame + encode of a new frame with CRC, against the same Javolution baselines and
 * against Javolution behind the same CRC check.
 */
private fun codec() {
    val results = Runner(OptionsBuilder().include("org.pocketbot.bench.StateCodecBench").addProfiler(GCProfiler::class.java).build()).run()
    val score = results.associate { it.params.benchmark.substringAfterLast('.') to it.primaryResult.score }
    // Heap bytes allocated per operation (JMH's GC profiler): what bounds both codecs here.
    val alloc = results.associate { r ->
        r.params.benchmark.substringAfterLast('.') to
            r.secondaryResults.entries.firstOrNull { it.key.endsWith("gc.alloc.rate.norm") }?.value?.score
    }
    // On a shared machine one run's mean moves with the neighbours' load; the best 1 s iteration of each benchmark
    // is the least disturbed one, so its ratios are printed too (suffix _best_iteration).
    val best = results.associate { r ->
        r.params.benchmark.substringAfterLast('.') to
            r.benchmarkResults.flatMap { it.iterationResults }.maxOf { it.primaryResult.score }
    }
    fun bestRatio(metric: String, a: String, b: String) = line(metric, "%.1fx".format(best.getValue(a) / best.getValue(b)))
    fun s(name: String) = score.getValue(name)
    fun bytes(metric: String, bench: String) = alloc[bench]?.let { line(metric, "%.0f".format(it)) }
    fun rate(metric: String, bench: String) = line(metric, "%.0f".format(s(bench)))
    fun ratio(metric: String, a: String, b: String) = line(metric, "%.1fx".format(s(a) / s(b)))
    val jNew = "javolutionNewStructPerPacket"
    val jReused = "javolutionReusedStruct"
    // payload level
    rate("payload_decode_encode_per_s", "sdkPayloadDecodeEncode")
    rate("payload_decode_only_per_s", "sdkPayloadDecode")
    rate("payload_encode_only_per_s", "sdkPayloadEncode")
    rate("javolution_state_decode_per_s", jNew)
    rate("javolution_reused_struct_decode_per_s", jReused)
    rate("javolution_decode_encode_per_s", "javolutionDecodeEncode")
    ratio("payload_speedup_vs_javolution", "sdkPayloadDecodeEncode", jNew)
    ratio("payload_speedup_vs_javolution_reused_struct", "sdkPayloadDecodeEncode", jReused)
    ratio("payload_speedup_vs_javolution_decode_encode", "sdkPayloadDecodeEncode", "javolutionDecodeEncode")
    ratio("payload_decode_only_speedup_vs_javolution", "sdkPayloadDecode", jNew)
    ratio("payload_decode_only_speedup_vs_javolution_reused_struct", "sdkPayloadDecode", jReused)
    // frame level
    rate("state_decode_encode_per_s", "sdkFrameDecodeEncode")
    rate("state_decode_only_per_s", "sdkFrameDecode")
    rate("state_encode_only_per_s", "sdkFrameEncode")
    rate("state_frame_crc_per_s", "crcOnly")
    rate("javolution_frame_crc_decode_per_s", "javolutionFrameNewStructPerPacket")
    ratio("codec_speedup_vs_javolution", "sdkFrameDecodeEncode", jNew)
    ratio("codec_speedup_vs_javolution_reused_struct", "sdkFrameDecodeEncode", jReused)
    ratio("codec_speedup_vs_javolution_with_crc", "sdkFrameDecodeEncode", "javolutionFrameNewStructPerPacket")
    ratio("decode_only_speedup_vs_javolution", "sdkFrameDecode", jNew)
    ratio("decode_only_speedup_vs_javolution_with_crc", "sdkFrameDecode", "javolutionFrameNewStructPerPacket")
    bestRatio("payload_speedup_vs_javolution_best_iteration", "sdkPayloadDecodeEncode", jNew)
    bestRatio("payload_speedup_vs_javolution_reused_struct_best_iteration", "sdkPayloadDecodeEncode", jReused)
    bestRatio("codec_speedup_vs_javolution_best_iteration", "sdkFrameDecodeEncode", jNew)
    bestRatio("codec_speedup_vs_javolution_reused_struct_best_iteration", "sdkFrameDecodeEncode", jReused)
    bytes("payload_decode_encode_alloc_bytes_per_op", "sdkPayloadDecodeEncode")
    bytes("payload_decode_alloc_bytes_per_op", "sdkPayloadDecode")
    bytes("state_decode_encode_alloc_bytes_per_op", "sdkFrameDecodeEncode")
    bytes("javolution_state_decode_alloc_bytes_per_op", jNew)
    bytes("javolution_reused_struct_decode_alloc_bytes_per_op", jReused)
}

/** Connect seven emulated robots at once (fresh settings cache: full read), handshake and all settings. */
private fun connect() {
    val times = (1..3).map {
        Emulator.local(robots = 7).use { emu ->
            emu.start(Speed.Realtime(1.0))
            val ms = runBlocking {
                delay(100) // let the firmware boot
                val fleet = Fleet(this, RobotOptions { settingsCache = InMemorySettingsCache() })
                val devices = emu.discoverer().discover().toList()
                val t0 = System.nanoTime()
                fleet.connectAll(devices)
                val ms = (System.nanoTime() - t0) / 1e6
                fleet.disconnect()
                ms
            }
            emu.stop()
            ms
        }
    }
    line("connect7_total_ms", "%.0f".format(times.sorted()[1]))
    line("connect7_runs_ms", times.joinToString("/") { "%.0f".format(it) })
}

/**
 * Seven robots in real time, each on its own simulated 115200-baud link (reached over TCP): six in full mode at
 * 100 Hz, one in reduced mode at a 2 ms period (more than its link carries). Delivered state updates per second
 * are compared with what each link can carry at that frame size (10 bits per SLIP byte), and the host-side
 * latency from a state frame's last byte written to the SDK's socket (StampingProxy) through the SDK's TcpTransport
 * (the SLIP stream transport over a socket: the same reader and decoder serial and Bluetooth links use)
 * to the StateFlow emission is timed.
 */
private fun realtime() {
    val baud = 115_200.0
    Emulator.local(robots = 7).use { emu ->
        emu.start(Speed.Realtime(1.0))
        emu.startTcp(basePort = 0)
        val proxies = emu.robots.map { StampingProxy(it.tcpPort) }
        val devices = emu.robots.mapIndexed { i, r -> org.pocketbot.sdk.transport.TcpRobotDevice("127.0.0.1", proxies[i].port, r.name) }
        val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
        val fleet = Fleet(scope, RobotOptions { settingsCache = InMemorySettingsCache() })
        val robots = runBlocking { fleet.connectAll(devices) }
        val latencies = java.util.concurrent.ConcurrentLinkedQueue<Long>()
        var measuring = false
        runBlocking {
            robots.forEachIndexed { i, r ->
                if (i < 6) r.reflector.set(SyncMode.FULL, 10.milliseconds) else r.reflector.set(SyncMode.REDUCED, 2.milliseconds)
            }
        }
        robots.forEachIndexed { i, r ->
            val arrivals = proxies[i].arrivals
            // Unconfined: the collector runs inside the emission, so its clock reading is the emission time.
            scope.launch(Dispatchers.Unconfined) {
                r.stateUpdates.collect { u: StateUpdate ->
                    val now = System.nanoTime()
                    val at = arrivals.remove(u.timeMs)
                    if (measuring && at != null) latencies += now - at
                }
            }
        }
        runBlocking { delay(2000) }
        val before = robots.map { it.linkStats.value }
        measuring = true
        val t0 = System.nanoTime()
        runBlocking { delay(10_000) }
        val seconds = (System.nanoTime() - t0) / 1e9
        measuring = false
        val after = robots.map { it.linkStats.value }

        val fullFrame = Slip.encode(Frames.encode(org.pocketbot.protocol.StateFull(org.pocketbot.protocol.RobotState.decode(ByteArray(org.pocketbot.protocol.ProtocolInfo.STATE_SIZE), 0)), 1)).size
        val reducedFrame = Slip.encode(Frames.encode(StateReduced(1, 1, 1, 1, 1, 1, 1), 1)).size
        val fullCapacity = baud / 10 / fullFrame
        val reducedCapacity = baud / 10 / reducedFrame
        val fullRates = (0 until 6).map { (after[it].fullStates - before[it].fullStates) / seconds }
        val reducedRate = (after[6].reducedStates - before[6].reducedStates) / seconds
        val fullShare = fullRates.map { it / minOf(100.0, fullCapacity) }
        val reducedShare = reducedRate / reducedCapacity
        line("realtime_full_updates_per_s", fullRates.joinToString("/") { "%.1f".format(it) })
        line("realtime_full_link_capacity_per_s", "%.1f".format(fullCapacity))
        line("realtime_full_delivered_share", "%.1f%%".format(100 * fullShare.min()))
        line("realtime_reduced_updates_per_s", "%.1f".format(reducedRate))
        line("realtime_reduced_link_capacity_per_s", "%.1f".format(reducedCapacity))
        line("realtime_reduced_delivered_share", "%.1f%%".format(100 * reducedShare))
        line("realtime_delivered_share_min", "%.1f%%".format(100 * minOf(fullShare.min(), reducedShare)))
        val sorted = latencies.sorted()
        if (sorted.isNotEmpty()) {
            fun pct(p: Double) = sorted[minOf(sorted.size - 1, (p * sorted.size).toInt())] / 1e6
            line("state_latency_samples", sorted.size.toString())
            line("state_latency_p50_ms", "%.3f".format(pct(0.50)))
            line("state_latency_p99_ms", "%.3f".format(pct(0.99)))
            line("state_latency_max_ms", "%.3f".format(sorted.last() / 1e6))
        }
        line("realtime_dropped_frames", after.sumOf { it.dropped }.toString())
        fleet.close()
        scope.cancel()
        proxies.forEach { it.close() }
        emu.stop()
    }
}

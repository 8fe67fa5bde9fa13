package org.pocketbot.bench

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import org.openjdk.jmh.runner.Runner
import org.openjdk.jmh.runner.options.OptionsBuilder
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.StateReduced
import org.pocketbot.protocol.SyncMode
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.StateUpdate
import kotlin.time.Duration.Companion.milliseconds

/**
 * `make bench-sdk`: every result is one line `sdk <metric>=<value>`; ratios are taken within this one run.
 *
 *   java -cp sdk/bench/target/classes:$(cat sdk/bench/target/classpath.txt) org.pocketbot.bench.SdkBenchKt [codec] [realtime] [connect]
 */
fun main(args: Array<String>) {
    val which = args.toSet().ifEmpty { setOf("codec", "realtime", "connect") }
    if ("codec" in which) codec()
    if ("connect" in which) connect()
    if ("realtime" in which) realtime()
}

private fun line(metric: String, value: String) = println("sdk $metric=$value")

private fun codec() {
    val results = Runner(OptionsBuilder().include("org.pocketbot.bench.StateCodecBench").build()).run()
    val score = results.associate { it.params.benchmark.substringAfterLast('.') to it.primaryResult.score }
    val sdk = score.getValue("sdkDecodeEncode")
    val jNew = score.getValue("javolutionNewStructPerPacket")
    val jReused = score.getValue("javolutionReusedStruct")
    line("state_decode_encode_per_s", "%.0f".format(sdk))
    line("state_decode_only_per_s", "%.0f".format(score.getValue("sdkDecode")))
    line("state_frame_crc_per_s", "%.0f".format(score.getValue("crcOnly")))
    line("javolution_state_decode_per_s", "%.0f".format(jNew))
    line("javolution_reused_struct_decode_per_s", "%.0f".format(jReused))
    line("codec_speedup_vs_javolution", "%.1fx".format(sdk / jNew))
    line("codec_speedup_vs_javolution_reused_struct", "%.1fx".format(sdk / jReused))
    line("decode_only_speedup_vs_javolution", "%.1fx".format(score.getValue("sdkDecode") / jNew))
}

/** Connect seven emulated robots at once (fresh settings cache: full read), handshake and all settings. */
private fun connect() {
    val times = (1..3).map {
        Emulator.local(robots = 7).use { emu ->
            emu.start(Speed.Realtime(1.0))
            runBlocking { delay(100) } // let the firmware boot
            val fleet = Fleet(options = RobotOptions(settingsCache = InMemorySettingsCache()))
            val devices = runBlocking { emu.discoverer().discover().toList() }
            val t0 = System.nanoTime()
            runBlocking { fleet.connectAll(devices) }
            val ms = (System.nanoTime() - t0) / 1e6
            fleet.close()
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
 * latency from a state frame's last byte leaving the transport's SLIP decoder to the StateFlow emission is timed.
 */
private fun realtime() {
    val baud = 115_200.0
    Emulator.local(robots = 7).use { emu ->
        emu.start(Speed.Realtime(1.0))
        emu.startTcp(basePort = 0)
        val devices = emu.robots.map { BenchTcpDevice(it.name, it.tcpPort) }
        val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
        val fleet = Fleet(scope, RobotOptions(settingsCache = InMemorySettingsCache()))
        val robots = runBlocking { fleet.connectAll(devices) }
        val latencies = java.util.concurrent.ConcurrentLinkedQueue<Long>()
        var measuring = false
        runBlocking {
            robots.forEachIndexed { i, r ->
                if (i < 6) r.reflector.set(SyncMode.FULL, 10.milliseconds) else r.reflector.set(SyncMode.REDUCED, 2.milliseconds)
            }
        }
        robots.forEachIndexed { i, r ->
            val arrivals = devices[i].arrivals
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

        val fullFrame = Slip.encode(Frames.encode(org.pocketbot.protocol.StateFull(robots[0].state.value), 1)).size
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
        emu.stop()
    }
}

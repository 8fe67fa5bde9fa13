package org.pocketbot.desktop.bench

import androidx.compose.runtime.mutableStateOf
import androidx.compose.ui.ImageComposeScene
import androidx.compose.ui.unit.Density
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.desktop.model.EmulatorModel
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.desktop.ui.View
import org.pocketbot.protocol.ColourMode
import org.pocketbot.protocol.SyncMode
import org.pocketbot.sdk.Controller
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * `make bench-desktop`: the panel with 7 robots at 100 Hz full state and one tuned robot in reduced mode at the
 * fastest period its link carries ([org.pocketbot.sdk.Tuner.samplePeriod]), drawn off screen at 60 frames a second.
 * Prints, as `desktop <metric>=<value>`:
 * the share of the tuned robot's samples that reached the chart (goal 100 %), and the composition + layout + drawing
 * time of a frame (p50, p95; goal p95 <= 16 ms), on the tuning view and on the fleet overview.
 *
 * Arguments: `--seconds N` per view (default 10).
 */
fun main(args: Array<String>) = runBlocking {
    val seconds = args.indexOf("--seconds").takeIf { it >= 0 }?.let { args[it + 1].toInt() } ?: 10
    val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
    val emulator = EmulatorModel(scope, "round", robots = 8)
    val panel = PanelModel(scope, emptyMap(), emulator)
    try {
        val robots = withTimeout(60.seconds) { panel.connectEmbedded() }
        check(robots.size == 8) { "connected ${robots.size} of 8 robots" }
        val tuned = robots.first()
        for (r in robots.drop(1)) {
            r.robot.reflector.set(SyncMode.FULL, 10.milliseconds)
            r.startLineFollowing(0.15, ColourMode.PLAIN)
        }
        panel.select(tuned)
        tuned.tuning.choose(Controller.LINE)
        tuned.startLineFollowing(0.15, ColourMode.PLAIN)
        tuned.tuning.start()
        tuned.tuning.active.first { it }
        delay(500)

        val view = mutableStateOf(View.TUNING)
        val scene = ImageComposeScene(1440, 900, Density(1f)) { PanelApp(panel, view) }
        try {
            val charted0 = tuned.tuning.live.added.get()
            val sent0 = tuned.robot.linkStats.value.reducedStates
            val tuning = frames(scene, seconds)
            delay(100) // the last samples on their way
            val charted = tuned.tuning.live.added.get() - charted0
            val sent = tuned.robot.linkStats.value.reducedStates - sent0
            view.value = View.OVERVIEW
            val overview = frames(scene, seconds)
            println("desktop robots=8 (7 at 100 Hz full state, 1 tuned at ${1000 / tuned.tuning.samplePeriod.inWholeMilliseconds} Hz reduced)")
            println("desktop tuned_samples_sent=$sent")
            println("desktop tuned_samples_charted_pct=%.2f".format(100.0 * charted / sent))
            println("desktop tuning_frame_ms_p50=%.2f".format(tuning.percentile(50)))
            println("desktop tuning_frame_ms_p95=%.2f".format(tuning.percentile(95)))
            println("desktop overview_frame_ms_p50=%.2f".format(overview.percentile(50)))
            println("desktop overview_frame_ms_p95=%.2f".format(overview.percentile(95)))
        } finally {
            scene.close()
        }
    } finally {
        panel.close()
        scope.cancel()
    }
}

/** Renders a frame every 1/60 s for [seconds]; returns the time each render took, in ms. */
private suspend fun frames(scene: ImageComposeScene, seconds: Int): DoubleArray {
    val times = ArrayList<Double>()
    val start = System.nanoTime()
    var next = start
    while (System.nanoTime() - start < seconds * 1_000_000_000L) {
        val t0 = System.nanoTime()
        scene.render(t0 - start)
        times += (System.nanoTime() - t0) / 1e6
        next += 16_666_667
        val wait = (next - System.nanoTime()) / 1_000_000
        if (wait > 0) delay(wait) else next = System.nanoTime()
    }
    return times.drop(30).toDoubleArray() // the first frames compose everything for the first time
}

private fun DoubleArray.percentile(p: Int): Double = sorted()[((size - 1) * p / 100.0).toInt()]
